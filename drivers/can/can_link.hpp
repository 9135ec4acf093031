// GovernorLink over CAN (can+udp or can+socketcan) with the J1939 map of j1939.hpp.
//   configure()  open the endpoint (client role); in TSC1 mode warnings() names its coarse
//                resolution
//   activate()   0xFF50 {bias 0, enable 01}
//   write(b)     0xFF50 {bias, enable as activated, counter+1}: the counter is the heartbeat
//   advance(n)   0xFF52 {n} (sim only, the CAN equivalent of Modbus holding 100); the plant
//                answers with one 0xFF51 carrying the counter of its last tick
//   read()       waits for a 0xFF51 of a plant tick not returned before (after advance(n):
//                exactly the last counter + n) and for the 0xFF53 echo of the last command
//                sent, then drains frames already queued so the sample is the latest.
//                0xFF53 fills bias_echo_pct and status, 0xFF51 power, counter and status
//                (status: whichever arrived last), EEC1 speed_rpm, GTACP power. Frames from
//                other source addresses are ignored.
//   deactivate() ramp, then 0xFF50 {0, enable 00}
// Idle frame: while the link is not activated, advance() and read() first send 0xFF50
// {bias 0, enable 00} unless a command went out since the last read. It changes nothing at the
// governor (the bias is off already), keeps the heartbeat moving, and makes the governor
// answer: a can+udp node learns its peer from it, and a governor that answers commands
// (plantsim's default in realtime) sends the 0xFF51 the read waits for.
// With ?command=tsc1&sync_rpm=N the commands go out as TSC1 speed requests instead (see
// CanCommand in link_uri.hpp); disable and the idle frame are TSC1 "no override" (mode 00);
// the heartbeat is TSC1's own 4-bit counter.
// CAN carries no frequency or voltage: those Sample fields stay 0. plant_time_s is
// counter * LinkOptions::plant_tick when that is set (the counter is unwrapped past 65535).
#pragma once

#include <linux/can.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/link_base.hpp"
#include "drivers/link_uri.hpp"

namespace drivers {

namespace can {
class CanEndpoint;
}

class CanLink final : public LinkBase {
 public:
  CanLink(LinkUri uri, const LinkOptions& options);
  ~CanLink() override;

  LinkResult<void> configure() override;
  LinkResult<void> activate() override { return send_command(0.0, true, "activate"); }
  LinkResult<void> write(double bias_pct) override;
  LinkResult<Sample> read() override;
  LinkResult<void> advance(std::uint16_t ticks) override;
  void close() override;
  std::string uri() const override { return uri_.text; }
  // The last 0xFF53 echo: the bias the governor applies (kUnavailable before the first one).
  LinkResult<double> read_held_bias() override;

  // One line each, for the caller to print (the link has no logger); set by configure().
  // TSC1 mode: its resolution, 0.125 rpm = 12.5 / sync_rpm % of bias.
  std::vector<std::string> warnings() const { return warnings_; }

 protected:
  LinkResult<void> disable() override { return send_command(0.0, false, "deactivate"); }

 private:
  struct ReadState {
    bool fresh = false;    // the awaited 0xFF51 is in
    bool saw_old = false;  // a 0xFF51 of a tick already returned came in
  };
  LinkResult<void> send_command(double bias_pct, bool enable, const char* call);
  LinkResult<void> send_idle_if_due(const char* call);
  LinkResult<void> apply(const can_frame& f, ReadState& st);
  LinkResult<void> apply_sample(const can_frame& f, ReadState& st);
  void apply_echo(const can_frame& f);
  LinkResult<Sample> missing(const ReadState& st) const;
  LinkResult<Sample> finish(std::chrono::steady_clock::time_point now);

  LinkUri uri_;
  std::unique_ptr<can::CanEndpoint> endpoint_;
  CounterCheck counter_;
  std::vector<std::string> warnings_;
  bool enabled_ = false;
  bool command_since_read_ = false;
  bool awaiting_echo_ = false;  // the last command's 0xFF53 has not come in yet
  bool echo_seen_ = false;      // a 0xFF53 has come in since configure()
  std::uint8_t tx_counter_ = 0;
  Sample sample_;
  std::optional<std::uint16_t> target_;  // counter awaited by this read (lockstep)
  std::uint64_t unwrapped_ = 0;          // sample counter without 16-bit wrap
  std::optional<std::uint16_t> last_seen_;
};

std::unique_ptr<GovernorLink> make_can_link(const LinkUri& uri, const LinkOptions& options);

// CanLink::warnings() of `link`, none for other links.
std::vector<std::string> link_warnings(const GovernorLink& link);

}  // namespace drivers
