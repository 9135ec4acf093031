#include "drivers/link_base.hpp"

#include <cmath>
#include <thread>

namespace drivers {

void CounterCheck::reset() {
  last_.reset();
  pending_ticks_ = 0;
}

LinkResult<void> CounterCheck::check(std::uint16_t counter, Clock::time_point now,
                                     const std::string& where) {
  const std::uint32_t expected = pending_ticks_;
  pending_ticks_ = 0;
  if (!last_) {
    last_ = counter;
    last_change_ = now;
    return {};
  }
  const auto moved = static_cast<std::uint16_t>(counter - *last_);  // modulo 2^16
  const std::uint16_t previous = *last_;
  if (moved != 0) {
    last_ = counter;
    last_change_ = now;
  }
  if (expected != 0) {
    if (moved == 0) {
      return LinkError{LinkErrorKind::kStale, where,
                       "sample counter stayed at " + std::to_string(counter) + " after " +
                           std::to_string(expected) + " tick(s) were advanced"};
    }
    if (moved != static_cast<std::uint16_t>(expected)) {
      return LinkError{LinkErrorKind::kProtocol, where,
                       "sample counter moved " + std::to_string(previous) + " -> " +
                           std::to_string(counter) + ", expected +" + std::to_string(expected)};
    }
    return {};
  }
  if (moved == 0 && !options_.lockstep && now - last_change_ > options_.stale_timeout) {
    const auto ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(now - last_change_).count();
    return LinkError{LinkErrorKind::kStale, where,
                     "sample counter stuck at " + std::to_string(counter) + " for " +
                         std::to_string(ms) + " ms"};
  }
  return {};
}

LinkError LinkBase::not_configured(const std::string& call) const {
  return LinkError{LinkErrorKind::kConfig, uri(), call + " called before configure()"};
}

// Linear ramp b_i = b0 (1 - i/N), N = ceil(|b0| / (rate * period)), so the governor never sees
// a step larger than rate * period when the external bias is withdrawn. b0 is the bias the
// governor applies now, read back (read_held_bias, kHeldBiasReads tries): after a refused or
// late write the last acknowledged value is stale, and ramping from it would raise the bias
// again first. When the governor cannot be asked, b0 is the last bias sent (what it holds if
// that write landed late); the supervisor's ramp before this only ever moved the bias towards
// the baseline, so that is never farther out than what the governor holds.
constexpr int kHeldBiasReads = 3;

LinkResult<void> LinkBase::deactivate() {
  double start_pct = last_sent_pct_;
  for (int i = 0; i < kHeldBiasReads; ++i) {
    if (auto held = read_held_bias(); held) {
      start_pct = held.value();
      break;
    }
  }
  ramp_start_pct_ = start_pct;
  const double period_s = std::chrono::duration<double>(options_.ramp_period).count();
  const double step_pct = options_.ramp_rate_pct_per_s * period_s;
  const int steps =
      step_pct > 0.0 ? static_cast<int>(std::ceil(std::abs(start_pct) / step_pct)) : 0;
  for (int i = 1; i <= steps; ++i) {
    auto r = write(start_pct * (1.0 - static_cast<double>(i) / steps));
    if (r && options_.lockstep) r = advance(options_.ramp_ticks_per_step);
    if (!r) {
      (void)disable();  // best effort: the governor's heartbeat rule is the last resort
      return r;
    }
    if (!options_.lockstep) std::this_thread::sleep_for(options_.ramp_period);
  }
  return disable();
}

}  // namespace drivers
