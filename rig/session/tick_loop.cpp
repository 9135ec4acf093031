#include "rig/session/tick_loop.hpp"

#include <fmt/format.h>

#include <cmath>
#include <thread>

namespace rig::session {

const char* to_string(Phase phase) {
  switch (phase) {
    case Phase::kSteady: return "steady";
    case Phase::kPilot: return "pilot";
    case Phase::kExcite: return "excite";
    case Phase::kSweep: return "sweep";
  }
  return "?";
}

const std::vector<std::string>& recording_columns() {
  static const std::vector<std::string> columns = {
      "t",       "u",        "y",           "speed_rpm",     "freq_hz", "status",
      "phase",   "request",  "bias_echo",   "plant_time_s",  "counter"};
  return columns;
}

TickLoop::TickLoop(drivers::GovernorLink& link, const TestConfig& config,
                   io::RecordingWriter& recorder, LiveView& view,
                   const std::atomic<bool>* abort)
    : link_(link),
      config_(config),
      recorder_(recorder),
      view_(view),
      abort_(abort),
      dt_s_(1.0 / config.link.sample_rate_hz),
      start_(std::chrono::steady_clock::now()) {
  status_.band_pct = config.safety.band_pct;
}

void TickLoop::set_phase(Phase phase) {
  phase_ = phase;
  status_.phase = to_string(phase);
  status_.peak_deviation_pct = 0.0;
  event("phase", to_string(phase));
}

void TickLoop::event(const std::string& kind, const std::string& text) {
  events_.push_back({t_s(), kind, text});
  if (kind != "phase") view_.message(fmt::format("[{:8.2f} s] {}: {}", t_s(), kind, text));
}

bool TickLoop::link_gone() const {
  return failures_ > static_cast<int>(config_.link.sample_rate_hz);
}

// Realtime: one exchange per sample period on the monotonic clock. Lockstep: as fast as the
// plant answers (the plant's clock only moves on advance()).
void TickLoop::pace() {
  if (config_.link.lockstep_ticks > 0) return;
  const auto due = start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(t_s()));
  std::this_thread::sleep_until(due);
}

drivers::LinkResult<drivers::Sample> TickLoop::exchange_read() {
  if (config_.link.lockstep_ticks > 0) {
    auto advanced = link_.advance(static_cast<std::uint16_t>(config_.link.lockstep_ticks));
    if (!advanced) return advanced.error();
  }
  return link_.read();
}

TickResult TickLoop::observe() {
  pace();
  TickResult r;
  r.t_s = t_s();
  auto read = exchange_read();
  if (read) {
    failures_ = 0;
    r.sample = read.value();
    record(read.value(), 0.0, 0.0);
  } else {
    ++failures_;
  }
  last_read_ = std::move(read);
  ++ticks_;
  return r;
}

TickResult TickLoop::prime() {
  pace();
  TickResult r;
  r.t_s = t_s();
  auto written = link_.write(0.0);
  auto read = exchange_read();
  if (read && written) {
    failures_ = 0;
  } else {
    ++failures_;
  }
  if (read) {
    r.sample = read.value();
    record(read.value(), 0.0, 0.0);
  }
  last_read_ = std::move(read);
  ++ticks_;
  return r;
}

TickResult TickLoop::supervised(Supervisor& sup, double request_pct) {
  pace();
  if (abort_requested() && !sup.tripped()) {
    sup.trip(TripCause::kExternal, "operator abort (SIGINT)");
    event("abort", "operator abort: ramping the bias back to baseline");
  }
  TickResult r;
  r.t_s = t_s();
  if (last_read_) {
    r.out = sup.tick(*last_read_, request_pct);
  } else {
    r.out = sup.tick_missing(request_pct);
  }
  bool ok = true;
  if (auto written = link_.write(r.out.bias_pct); !written) {
    ok = false;
    if (!sup.tripped()) sup.trip(TripCause::kLinkError, written.error().message());
  }
  auto read = exchange_read();
  if (read && ok) {
    failures_ = 0;
  } else {
    ++failures_;
  }
  if (read) {
    r.sample = read.value();
    record(read.value(), r.out.excitation_pct, request_pct);
  }
  status_.bias_pct = r.out.bias_pct;
  last_read_ = std::move(read);
  ++ticks_;
  return r;
}

void TickLoop::record(const drivers::Sample& s, double u_pct, double request_pct) {
  const double deviation_pct = p0_kw_ > 0.0 ? 100.0 * (s.power_kw - p0_kw_) / p0_kw_ : 0.0;
  if (std::isfinite(deviation_pct)) {
    status_.deviation_pct = deviation_pct;
    status_.peak_deviation_pct = std::max(status_.peak_deviation_pct, std::abs(deviation_pct));
    max_dev_pct_ = phase_ == Phase::kSteady ? max_dev_pct_
                                              : std::max(max_dev_pct_, std::abs(deviation_pct));
  }
  status_.elapsed_s = t_s();
  // Non-finite readings are not written: the recording must stay readable by `rig
  // identify`; the trip they cause is in the events and the report.
  const bool finite = std::isfinite(s.power_kw) && std::isfinite(s.speed_rpm) &&
                      std::isfinite(s.freq_hz);
  if (finite) {
    recorder_.append({t_s(), u_pct, s.power_kw, s.speed_rpm, s.freq_hz,
                      static_cast<double>(s.status), static_cast<double>(phase_), request_pct,
                      s.bias_echo_pct, s.plant_time_s, static_cast<double>(s.counter)});
  }
  if (ticks_ % static_cast<std::uint64_t>(std::max(1.0, config_.link.sample_rate_hz / 10.0)) == 0 &&
      finite) {
    trace_.t_s.push_back(t_s());
    trace_.deviation_pct.push_back(deviation_pct);
    trace_.u_pct.push_back(u_pct);
  }
  show();
}

void TickLoop::show(bool force) { view_.update(status_, force); }

}  // namespace rig::session
