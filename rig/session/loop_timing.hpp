// Cycle timing of the tick loop (DESIGN.md section 6, "jitter is measured and recorded").
//
// Realtime: cycle k is due at t0 + k dt on the monotonic clock. Its lateness is
// (actual start after the sleep) - (due time): the scheduler's wake-up latency when the
// previous cycle finished in time, plus the overrun when it did not. A cycle that reaches its
// due time with nothing left to sleep (the previous cycle's work ran past it) is an overrun.
// Lockstep: there is no schedule; the wall time per exchange (cycle start to the end of the
// read, i.e. supervisor, write, advance and read) is what limits the speed.
// The exchange time is measured in both modes.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace rig::session {

// Histogram of a per-cycle time: counts[i] cycles in [i bin_ms, (i + 1) bin_ms).
struct TimingHistogram {
  double bin_ms = 0.0;
  std::vector<double> counts;
};

struct LoopTimingSummary {
  std::string mode;        // "realtime" or "lockstep"
  double period_ms = 0.0;  // scheduled period (realtime) or plant time per exchange (lockstep)
  std::size_t cycles = 0;
  // Realtime only: lateness of the cycle start against its schedule.
  double jitter_p50_ms = 0.0, jitter_p99_ms = 0.0, jitter_max_ms = 0.0, jitter_mean_ms = 0.0;
  std::size_t overruns = 0;
  std::size_t slips = 0;           // cycles late by more than a period: the schedule moved
  double slip_total_ms = 0.0;      // by this much in all
  bool realtime_priority = false;  // the tick loop ran under SCHED_FIFO
  bool cpu_latency_held = false;   // every CPU kept out of deep idle states (cpu_latency.hpp)
  // Both modes: wall time from the cycle start to the end of the read.
  double exchange_p50_ms = 0.0, exchange_p99_ms = 0.0, exchange_max_ms = 0.0;
  double exchange_mean_ms = 0.0;
  // For the report's charts: the histogram of the lateness (realtime) or of the exchange time
  // (lockstep), and the largest value of each second of test time.
  TimingHistogram histogram;
  std::vector<double> second_t_s, second_max_ms;
};

class LoopTimer {
 public:
  LoopTimer(bool realtime, double period_s);

  bool realtime() const { return realtime_; }
  // At the start of a cycle at test time t_s (realtime only: lateness >= 0, whether the cycle
  // had no time left to sleep, and whether the schedule moved by the lateness).
  void start(double t_s, double lateness_s, bool overrun, bool slip = false);
  // At the end of the read of the cycle most recently started.
  void exchange(double wall_s);
  void set_realtime_priority(bool fifo) { fifo_ = fifo; }
  void set_cpu_latency_held(bool held) { cpu_latency_held_ = held; }
  // A long run (rig monitor) keeps only the last `cycles` to 2 `cycles` cycles' timings, so
  // that memory stays flat; the summary then describes those (cycles counts them all).
  void set_window(std::size_t cycles) { window_ = cycles; }

  LoopTimingSummary summary() const;
  // The last n cycles only (cheap enough for the loop's thread to call every few seconds):
  // lateness (realtime) or exchange time (lockstep) p50, p99 and max, in ms.
  struct Recent {
    double p50_ms = 0.0, p99_ms = 0.0, max_ms = 0.0;
  };
  Recent recent(std::size_t n) const;
  // The last n cycles' lateness (realtime) or exchange time (lockstep), ms, oldest first.
  std::vector<float> last(std::size_t n) const;
  std::size_t cycles() const { return t_s_.size() + dropped_; }
  std::size_t overruns() const { return overruns_; }

 private:
  bool realtime_;
  double period_s_;
  std::vector<float> t_s_, lateness_ms_, exchange_ms_;
  std::size_t window_ = 0, dropped_ = 0;
  void trim();
  std::size_t overruns_ = 0;
  std::size_t slips_ = 0;
  double slip_total_s_ = 0.0;
  bool fifo_ = false;
  bool cpu_latency_held_ = false;
};

// The q-quantile (0..1) of values by the nearest-rank rule; 0 for an empty vector.
double quantile_ms(std::vector<float> values, double q);

}  // namespace rig::session
