// One tick of a test (DESIGN.md section 2): supervisor -> link.write(bias) -> (lockstep:
// advance) -> link.read() -> recorder -> consumer. Also the unsupervised observation used by
// the steady-state check, which writes nothing to the governor (only the simulator's clock).
#pragma once

#include <atomic>
#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "drivers/governor_link.hpp"
#include "rig/io/recording_writer.hpp"
#include "rig/live/feed.hpp"
#include "rig/session/cpu_latency.hpp"
#include "rig/session/live_publish.hpp"
#include "rig/session/live_view.hpp"
#include "rig/session/loop_timing.hpp"
#include "rig/session/supervisor.hpp"
#include "rig/session/test_config.hpp"

namespace rig::session {

// Phase codes of the recording's `phase` column.
enum class Phase { kSteady = 0, kPilot = 1, kExcite = 2, kSweep = 3, kMonitor = 4 };
const char* to_string(Phase phase);

struct Event {
  double t_s = 0.0;
  std::string kind;  // "phase", "trip", "link", "abort", "warning"
  std::string text;
};

// Recording columns, in order (docs/test-file.md lists them with units).
const std::vector<std::string>& recording_columns();

struct TickResult {
  std::optional<drivers::Sample> sample;  // the read of this tick, when it succeeded
  SupervisorOutput out;                   // what was written (supervised ticks)
  double t_s = 0.0;
};

class TickLoop {
 public:
  TickLoop(drivers::GovernorLink& link, const TestConfig& config, io::RecordingWriter& recorder,
           LiveView& view, const std::atomic<bool>* abort, live::Feed* feed = nullptr);
  ~TickLoop();  // back to normal scheduling when the realtime loop raised it
  TickLoop(const TickLoop&) = delete;
  TickLoop& operator=(const TickLoop&) = delete;

  // Steady phase: advance (lockstep) and read; nothing is written to the governor.
  TickResult observe();
  // After activation: writes the baseline bias (0) with a fresh heartbeat, then reads. The
  // steady-state check wrote nothing, so the governor may still flag the heartbeat as lost.
  TickResult prime();
  // A supervised tick: judge the latest sample, write the bias, advance, read, record.
  TickResult supervised(Supervisor& supervisor, double request_pct);

  // A long run (rig monitor): no full-rate recording unless keep_recording, no trace, the
  // last 10 to 20 minutes of cycle timings, and an operator abort ends the excitation through
  // the phase (a normal end) instead of tripping the supervisor.
  void configure_long_run(bool keep_recording);

  void set_phase(Phase phase);
  Phase phase() const { return phase_; }
  double t_s() const { return static_cast<double>(ticks_) * dt_s_; }
  double dt_s() const { return dt_s_; }
  void event(const std::string& kind, const std::string& text);
  const std::vector<Event>& events() const { return events_; }
  bool abort_requested() const { return abort_ != nullptr && abort_->load(); }
  // Consecutive failed reads/writes: the link is considered gone above a second's worth.
  bool link_gone() const;
  // The last link error of a read or write ("" when the last exchange succeeded).
  const std::string& last_link_error() const { return last_link_error_; }
  // A failure of the rig itself (the recording could not be written): "" while none. A
  // supervised tick turns it into a kRigFailure trip; nothing is thrown across the tick.
  const std::string& rig_failure() const { return rig_failure_; }
  LiveStatus& status() { return status_; }
  // Refreshes the terminal line and, with a live feed, publishes the status and timing.
  void show(bool force = false);
  // The live feed (estimates, sweep points, alarms are published by the phases).
  const LivePublisher& live() const { return live_; }
  // Power deviation (P - P0) / P0 % trace, decimated to ~10 Hz, for the report.
  struct Trace {
    std::vector<double> t_s, deviation_pct, u_pct;
  };
  const Trace& trace() const { return trace_; }
  void set_p0(double p0_kw) { p0_kw_ = p0_kw; }
  double max_abs_deviation_pct() const { return max_dev_pct_; }
  // Cycle timing: lateness against the schedule (realtime) and exchange wall time.
  const LoopTimer& timing() const { return timer_; }

 private:
  drivers::LinkResult<drivers::Sample> exchange_read();
  // Waits for this tick's due time (realtime) and starts its cycle timing.
  void pace();
  // Ends the cycle's exchange timing (after the read).
  void exchanged();
  void record(const drivers::Sample& s, double u_pct, double request_pct);

  drivers::GovernorLink& link_;
  const TestConfig& config_;
  io::RecordingWriter& recorder_;
  LiveView& view_;
  const std::atomic<bool>* abort_;
  double dt_s_;
  std::uint64_t ticks_ = 0;
  Phase phase_ = Phase::kSteady;
  std::vector<Event> events_;
  int failures_ = 0;
  std::optional<drivers::LinkResult<drivers::Sample>> last_read_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point cycle_start_;
  LoopTimer timer_;
  bool fifo_ = false;
  bool hold_cpu_latency_ = true;  // a long run (rig monitor) lets the CPUs idle
  CpuLatencyHold cpu_latency_;
  LiveStatus status_;
  LivePublisher live_;
  SupervisorState supervisor_state_ = SupervisorState::kIdle;
  Trace trace_;
  double p0_kw_ = 0.0;
  double max_dev_pct_ = 0.0;
  std::string last_link_error_;
  std::string rig_failure_;
  bool recording_ = true;
  bool tracing_ = true;
  bool abort_trips_ = true;
};

}  // namespace rig::session
