#include "rig/session/live_publish.hpp"

#include <algorithm>
#include <cmath>

namespace rig::session {

LivePublisher::LivePublisher(live::Feed* feed, double tick_rate_hz)
    : feed_(feed),
      every_ticks_(static_cast<std::uint64_t>(std::max(1.0, tick_rate_hz / kSampleRateHz))) {}

void LivePublisher::publish(const char* kind, const nlohmann::json& body) const {
  if (feed_ != nullptr) feed_->publish(kind, body);
}

bool LivePublisher::due(std::chrono::steady_clock::time_point& last, double interval_s,
                        bool force) {
  const auto now = std::chrono::steady_clock::now();
  if (!force && std::chrono::duration<double>(now - last).count() < interval_s) return false;
  last = now;
  return true;
}

void LivePublisher::sample(std::uint64_t tick, double t_s, double deviation_pct, double u_pct,
                           int phase, bool backing_off) {
  if (feed_ == nullptr || tick % every_ticks_ != 0 || !std::isfinite(deviation_pct)) return;
  feed_->publish(live::kind::kSample, {{"t_s", t_s},
                                       {"deviation_pct", deviation_pct},
                                       {"u_pct", u_pct},
                                       {"phase", phase},
                                       {"backoff", backing_off}});
}

void LivePublisher::state(const LiveStatus& s, SupervisorState supervisor, double p0_kw,
                          bool force) {
  if (feed_ == nullptr || !due(last_state_, kStateIntervalS, force)) return;
  nlohmann::json estimates = nlohmann::json::array();
  for (const auto& e : s.estimates) {
    estimates.push_back({{"name", e.name}, {"value", e.value}, {"std_error", e.std_error}});
  }
  feed_->publish(live::kind::kState,
                 {{"phase", s.phase},
                  {"t_s", s.elapsed_s},
                  {"eta_s", s.eta_s ? nlohmann::json(*s.eta_s) : nlohmann::json()},
                  {"deviation_pct", s.deviation_pct},
                  {"peak_deviation_pct", s.peak_deviation_pct},
                  {"band_pct", s.band_pct},
                  {"bias_pct", s.bias_pct},
                  {"p0_kw", p0_kw},
                  {"supervisor", to_string(supervisor)},
                  {"estimates", estimates},
                  {"flags", s.flags}});
}

void LivePublisher::event(double t_s, const std::string& kind, const std::string& text) const {
  if (feed_ != nullptr)
    feed_->publish(live::kind::kEvent, {{"t_s", t_s}, {"kind", kind}, {"text", text}});
}

void LivePublisher::timing(const LoopTimer& timer, double t_s, bool force) {
  if (feed_ == nullptr || !due(last_timing_, kTimingIntervalS, force)) return;
  // The last ~10 s of cycles at 100 Hz: the figure a person watching wants, cheap to compute.
  constexpr std::size_t kRecentCycles = 1000;
  // Each cycle's own figure since the previous message, in whole microseconds, so that a
  // reader can pool any stretch of the run exactly (scripts/bench live); bounded for a loop
  // that stalled for long.
  constexpr std::size_t kMaxListed = 2000;
  const LoopTimer::Recent r = timer.recent(kRecentCycles);
  const std::size_t fresh = std::min(kMaxListed, timer.cycles() - timed_cycles_);
  timed_cycles_ = timer.cycles();
  nlohmann::json cycles_us = nlohmann::json::array();
  for (float ms : timer.last(fresh)) cycles_us.push_back(std::lround(1e3 * ms));
  feed_->publish(live::kind::kTiming, {{"t_s", t_s},
                                       {"mode", timer.realtime() ? "realtime" : "lockstep"},
                                       {"p50_ms", r.p50_ms},
                                       {"p99_ms", r.p99_ms},
                                       {"max_ms", r.max_ms},
                                       {"cycles", timer.cycles()},
                                       {"overruns", timer.overruns()},
                                       {"cycles_us", cycles_us}});
}

}  // namespace rig::session
