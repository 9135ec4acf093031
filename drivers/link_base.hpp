// Lifecycle logic shared by the Modbus and CAN links: the sample-counter rule that detects a
// stale plant, and the bias ramp of deactivate().
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "drivers/governor_link.hpp"
#include "drivers/link_options.hpp"

namespace drivers {

// Sample counter rule (DESIGN.md section 8: any stale sample trips the test).
//   lockstep, after advance(n): the counter must have moved by exactly n
//     (0 -> kStale, another amount -> kProtocol);
//   realtime: the counter may repeat, but not for longer than stale_timeout (-> kStale).
class CounterCheck {
 public:
  using Clock = std::chrono::steady_clock;
  explicit CounterCheck(const LinkOptions& options) : options_(options) {}
  void expect_ticks(std::uint16_t n) { pending_ticks_ += n; }
  std::uint32_t pending_ticks() const { return pending_ticks_; }
  std::optional<std::uint16_t> last() const { return last_; }
  LinkResult<void> check(std::uint16_t counter, Clock::time_point now, const std::string& where);
  void reset();

 private:
  const LinkOptions& options_;
  std::optional<std::uint16_t> last_;
  std::uint32_t pending_ticks_ = 0;
  Clock::time_point last_change_{};
};

// Implements deactivate() on top of write()/advance(): the bias goes to zero in steps of
// ramp_rate * ramp_period, then disable() clears the enable bit.
class LinkBase : public GovernorLink {
 public:
  explicit LinkBase(LinkOptions options) : options_(options) {}
  LinkResult<void> deactivate() override;
  // Where the last deactivate() started its ramp (the bias read back from the governor).
  double ramp_start_pct() const { return ramp_start_pct_; }

 protected:
  virtual LinkResult<void> disable() = 0;  // writes bias 0 with the enable bit cleared
  LinkError not_configured(const std::string& call) const;

  LinkOptions options_;
  double last_bias_pct_ = 0.0;  // last bias written and acknowledged (after quantisation)
  // Last bias sent, acknowledged or not: what the governor holds if that write landed (a late
  // answer). Every link sets it before its write goes out.
  double last_sent_pct_ = 0.0;
  double ramp_start_pct_ = 0.0;
};

}  // namespace drivers
