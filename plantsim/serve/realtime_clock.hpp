// The realtime clock (DESIGN.md section 6): a thread that ticks the governor on the monotonic
// clock. Tick k (plant time k T -> (k+1) T) is due at start + (k+1) T and is taken after
// std::this_thread::sleep_until(due), so plant time equals elapsed monotonic time whenever
// the thread keeps up. Lateness (wake time - due time) is the tick jitter; it is kept in a
// 1 us histogram so p50/p99/max cost nothing per tick. A tick that is late is still taken
// (the plant catches up) so plant time never drifts from wall time.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "plantsim/serve/governor.hpp"

namespace plantsim::serve {

struct JitterStats {
  std::uint64_t ticks = 0;
  double p50_us = 0.0;
  double p99_us = 0.0;
  double max_us = 0.0;
  std::uint64_t late_over_1_tick = 0;  // ticks taken more than one period after they were due
};

// Accumulates lateness samples; percentiles from a histogram with 1 us bins up to 100 ms
// (anything later lands in the last bin; max is kept exactly).
class JitterHistogram {
 public:
  JitterHistogram();
  void add(std::chrono::nanoseconds lateness, std::chrono::nanoseconds period);
  JitterStats stats() const;

 private:
  std::vector<std::uint32_t> bins_;
  std::uint64_t count_ = 0;
  std::int64_t max_ns_ = 0;
  std::uint64_t late_ = 0;
};

class RealtimeClock {
 public:
  explicit RealtimeClock(Governor& governor);
  ~RealtimeClock();
  void start();
  void stop();  // joins; idempotent
  JitterStats jitter() const;
  // Whether the tick thread got SCHED_FIFO (valid once the first tick has been taken).
  bool realtime_priority() const { return realtime_priority_; }

 private:
  void run();
  void raise_priority();

  Governor& governor_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> realtime_priority_{false};
  mutable std::mutex mu_;
  JitterHistogram histogram_;
};

}  // namespace plantsim::serve
