#include "plantsim/serve/realtime_clock.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <algorithm>
#include <cmath>

namespace plantsim::serve {
namespace {
constexpr std::size_t kBins = 100001;  // 0 .. 100 ms in 1 us bins
}

JitterHistogram::JitterHistogram() : bins_(kBins, 0) {}

void JitterHistogram::add(std::chrono::nanoseconds lateness, std::chrono::nanoseconds period) {
  const std::int64_t ns = std::max<std::int64_t>(0, lateness.count());
  ++bins_[std::min<std::size_t>(kBins - 1, static_cast<std::size_t>(ns / 1000))];
  ++count_;
  max_ns_ = std::max(max_ns_, ns);
  if (lateness > period) ++late_;
}

JitterStats JitterHistogram::stats() const {
  JitterStats s;
  s.ticks = count_;
  s.max_us = static_cast<double>(max_ns_) / 1e3;
  s.late_over_1_tick = late_;
  if (count_ == 0) return s;
  // Percentile q: the smallest bin whose cumulative count reaches ceil(q n); report its upper
  // edge so the figure is an upper bound at 1 us resolution.
  const auto percentile = [&](double q) {
    const auto target = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
    std::uint64_t cumulative = 0;
    for (std::size_t i = 0; i < bins_.size(); ++i) {
      cumulative += bins_[i];
      if (cumulative >= target) return std::min(static_cast<double>(i + 1), s.max_us);
    }
    return s.max_us;
  };
  s.p50_us = percentile(0.50);
  s.p99_us = percentile(0.99);
  return s;
}

RealtimeClock::RealtimeClock(Governor& governor) : governor_(governor) {}

RealtimeClock::~RealtimeClock() { stop(); }

void RealtimeClock::start() {
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void RealtimeClock::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

JitterStats RealtimeClock::jitter() const {
  std::lock_guard lock(mu_);
  return histogram_.stats();
}

// Best effort: a 1 ns timer slack (the default 50 us would be half the p50 jitter budget) and
// SCHED_FIFO when the process may use it (root or CAP_SYS_NICE); otherwise normal scheduling.
void RealtimeClock::raise_priority() {
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  sched_param param{};
  param.sched_priority = std::min(50, sched_get_priority_max(SCHED_FIFO));
  realtime_priority_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
}

void RealtimeClock::run() {
  using Clock = std::chrono::steady_clock;
  raise_priority();
  const auto period = governor_.tick_period();
  const auto start = Clock::now() - governor_.snapshot().plant_time;
  std::uint64_t k = governor_.snapshot().ticks;
  while (!stop_) {
    const auto due = start + period * static_cast<std::int64_t>(k + 1);
    std::this_thread::sleep_until(due);
    const auto lateness = Clock::now() - due;
    governor_.tick();
    ++k;
    std::lock_guard lock(mu_);
    histogram_.add(std::chrono::duration_cast<std::chrono::nanoseconds>(lateness), period);
  }
}

}  // namespace plantsim::serve
