#include "rig/session/tick_loop.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cmath>
#include <thread>

namespace rig::session {

const char* to_string(Phase phase) {
  switch (phase) {
    case Phase::kSteady:
      return "steady";
    case Phase::kPilot:
      return "pilot";
    case Phase::kExcite:
      return "excite";
    case Phase::kSweep:
      return "sweep";
    case Phase::kMonitor:
      return "monitor";
  }
  return "?";
}

const std::vector<std::string>& recording_columns() {
  static const std::vector<std::string> columns = {
      "t",     "u",       "y",         "speed_rpm",    "freq_hz", "status",
      "phase", "request", "bias_echo", "plant_time_s", "counter"};
  return columns;
}

TickLoop::TickLoop(drivers::GovernorLink& link, const TestConfig& config,
                   io::RecordingWriter& recorder, LiveView& view, const std::atomic<bool>* abort,
                   live::Feed* feed)
    : link_(link),
      config_(config),
      recorder_(recorder),
      view_(view),
      abort_(abort),
      dt_s_(1.0 / config.link.sample_rate_hz),
      start_(std::chrono::steady_clock::now()),
      timer_(config.link.lockstep_ticks == 0, 1.0 / config.link.sample_rate_hz),
      live_(feed, config.link.sample_rate_hz) {
  status_.band_pct = config.safety.band_pct;
}

namespace {
// Realtime: the loop's thread runs under SCHED_FIFO when the process may use it (root or
// CAP_SYS_NICE), so that other work on the machine delays neither its wake-ups nor the light
// processing of a tick (supervisor, recorder, live view); below a co-located plant
// simulator's priority (50). Everything heavy (block estimates, phase-change work) runs on
// worker threads at normal priority (thread_priority.hpp). Without the permission: normal
// scheduling throughout; the report says which.
bool set_fifo(bool on) {
  sched_param param{};
  if (on) param.sched_priority = std::min(40, sched_get_priority_max(SCHED_FIFO));
  return pthread_setschedparam(pthread_self(), on ? SCHED_FIFO : SCHED_OTHER, &param) == 0;
}
}  // namespace

TickLoop::~TickLoop() {
  if (fifo_) set_fifo(false);
}

void TickLoop::set_phase(Phase phase) {
  phase_ = phase;
  status_.phase = to_string(phase);
  status_.peak_deviation_pct = 0.0;
  event("phase", to_string(phase));
}

void TickLoop::event(const std::string& kind, const std::string& text) {
  events_.push_back({t_s(), kind, text});
  live_.event(t_s(), kind, text);
  if (kind != "phase") view_.message(fmt::format("[{:8.2f} s] {}: {}", t_s(), kind, text));
}

bool TickLoop::link_gone() const {
  return failures_ > static_cast<int>(config_.link.sample_rate_hz);
}

// Realtime: one exchange per sample period on the monotonic clock, tick k due at
// t0 + k dt + slip (t0: the first tick). A cycle late by less than a period is caught up by
// the next one. A cycle late by more (a long estimate, a link hiccup) moves the schedule
// (slip += lateness) instead of following it with back-to-back exchanges, which would read
// the plant faster than it ticks (a stale-sample trip) and crowd samples of one plant state.
// Lockstep: as fast as the plant answers (the plant's clock only moves on advance()).
void TickLoop::pace() {
  using Clock = std::chrono::steady_clock;
  if (config_.link.lockstep_ticks > 0) {
    cycle_start_ = Clock::now();
    timer_.start(t_s(), 0.0, false);
    return;
  }
  if (ticks_ == 0) {
    fifo_ = set_fifo(true);
    timer_.set_realtime_priority(fifo_);
    timer_.set_cpu_latency_held(hold_cpu_latency_ && cpu_latency_.acquire());
    start_ = Clock::now();
  }
  const auto due =
      start_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t_s()));
  const auto arrived = Clock::now();
  const bool overrun = ticks_ > 0 && arrived >= due;  // no time left to sleep
  std::this_thread::sleep_until(due);
  cycle_start_ = Clock::now();
  const double late_s = std::chrono::duration<double>(cycle_start_ - due).count();
  const bool slip = late_s > dt_s_;
  if (slip) start_ += cycle_start_ - due;
  timer_.start(t_s(), late_s, overrun, slip);
}

void TickLoop::exchanged() {
  const auto now = std::chrono::steady_clock::now();
  timer_.exchange(std::chrono::duration<double>(now - cycle_start_).count());
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
  exchanged();
  if (read) {
    failures_ = 0;
    last_link_error_.clear();
    r.sample = read.value();
    record(read.value(), 0.0, 0.0);
  } else {
    ++failures_;
    last_link_error_ = read.error().message();
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
  exchanged();
  if (read && written) {
    failures_ = 0;
    last_link_error_.clear();
  } else {
    ++failures_;
    last_link_error_ = !written ? written.error().message() : read.error().message();
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
  if (abort_trips_ && abort_requested() && !sup.tripped()) {
    sup.trip(TripCause::kExternal, "operator abort (Ctrl-C, SIGTERM or the live page's Stop)");
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
    last_link_error_ = written.error().message();
    if (!sup.tripped()) sup.trip(TripCause::kLinkError, written.error().message());
  }
  auto read = exchange_read();
  exchanged();
  if (read && ok) {
    failures_ = 0;
    last_link_error_.clear();
  } else {
    ++failures_;
    if (!read) last_link_error_ = read.error().message();
  }
  supervisor_state_ = r.out.state;
  if (read) {
    r.sample = read.value();
    record(read.value(), r.out.excitation_pct, request_pct);
  }
  if (!rig_failure_.empty() && !sup.tripped()) sup.trip(TripCause::kRigFailure, rig_failure_);
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
    max_dev_pct_ =
        phase_ == Phase::kSteady ? max_dev_pct_ : std::max(max_dev_pct_, std::abs(deviation_pct));
  }
  status_.elapsed_s = t_s();
  // Non-finite readings are not written: the recording must stay readable by `rig
  // identify`; the trip they cause is in the events and the report.
  const bool finite =
      std::isfinite(s.power_kw) && std::isfinite(s.speed_rpm) && std::isfinite(s.freq_hz);
  if (finite && rig_failure_.empty() && recording_) {
    try {
      recorder_.append({t_s(), u_pct, s.power_kw, s.speed_rpm, s.freq_hz,
                        static_cast<double>(s.status), static_cast<double>(phase_), request_pct,
                        s.bias_echo_pct, s.plant_time_s, static_cast<double>(s.counter)});
    } catch (const std::exception& e) {
      // Nothing throws across the tick: the next supervised tick trips on it.
      rig_failure_ = std::string("cannot write the recording: ") + e.what();
    }
  }
  if (tracing_ &&
      ticks_ % static_cast<std::uint64_t>(std::max(1.0, config_.link.sample_rate_hz / 10.0)) == 0 &&
      finite) {
    trace_.t_s.push_back(t_s());
    trace_.deviation_pct.push_back(deviation_pct);
    trace_.u_pct.push_back(u_pct);
  }
  if (finite) {
    live_.sample(ticks_, t_s(), deviation_pct, u_pct, static_cast<int>(phase_),
                 supervisor_state_ == SupervisorState::kBackingOff);
  }
  show();
}

void TickLoop::configure_long_run(bool keep_recording) {
  recording_ = keep_recording;
  tracing_ = false;
  abort_trips_ = false;
  // Months of holding every CPU out of idle would cost power and heat for little: a monitor
  // records its slips instead.
  hold_cpu_latency_ = false;
  timer_.set_window(static_cast<std::size_t>(600.0 / dt_s_));
}

void TickLoop::show(bool force) {
  view_.update(status_, force);
  live_.state(status_, supervisor_state_, p0_kw_, force);
  live_.timing(timer_, t_s(), force);
}

}  // namespace rig::session
