// The governor's CAN face (DESIGN.md section 6 CAN map, drivers/can/j1939.hpp) over the
// drivers' can+udp or SocketCAN endpoint, node role.
//
// Received (only from CanNodeOptions::rig_address, default 0xF9; TSC1 only when addressed to
// the governor or global; anything else is counted in `wrong_source` and ignored):
//   PGN 0xFF50  bias, enable state, 4-bit counter + checksum. The counter is the heartbeat. A
//               frame with a bad checksum, a bias outside the SLOT's values or enable state 10
//               is ignored and counted; a frame whose counter is not the previous + 1 (mod 16)
//               is ignored and counted, and the counter is re-synchronised to it, so a
//               restarted rig is accepted again from its second frame. Enable state 11
//               ("don't care") keeps the enable as it was.
//   TSC1        speed request, for governors that only take TSC1. In DEGOV1 the speed error
//               and the bias enter the same summing junction in per unit, so a speed request n
//               is the bias 100 (n - n0) / n0 % with n0 the synchronous speed at start
//               (0.125 rpm/bit is 0.021 % at 600 rpm: coarse, as the rig warns). Override
//               mode 00 ("no override") clears the enable.
//   PGN 0xFF52  lockstep: advance exactly N ticks, then send one 0xFF51 carrying the last
//               tick's counter. Ignored in realtime.
// Sent:
//   PGN 0xFF53  one per accepted 0xFF50 / TSC1, at the tick the command takes effect: the bias
//               applied (after the governor's clamp), the bias received, that tick's counter,
//               status, and the command's counter.
//   PGN 0xFF51  lockstep: one per 0xFF52. Realtime: with sample_period 0 (default) one at every
//               tick that answered a command (after its 0xFF53), so the bus carries the rig's
//               rate; otherwise every sample_period of plant time.
//   EEC1 every 20 ms and GTACP every 100 ms of plant time; EEC1 byte 5 is the rig's address
//   while the external bias is active, the governor's own (0x00) otherwise.
// Over UDP nothing is sent until the rig's first frame names the peer.
#pragma once

#include <linux/can.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "drivers/can/transport.hpp"
#include "plantsim/serve/governor.hpp"
#include "plantsim/serve/modbus_node.hpp"

namespace plantsim::serve {

struct CanNodeOptions {
  std::uint8_t rig_address = 0xF9;  // drivers::j1939::kRigAddress
  // Realtime 0xFF51 period in plant time; 0: answer each command instead.
  std::chrono::nanoseconds sample_period{0};
};

struct CanCounters {
  std::uint64_t received = 0;
  std::uint64_t accepted = 0;      // commands, TSC1 and lockstep frames acted on
  std::uint64_t bad_checksum = 0;  // also malformed frames of a known PGN
  std::uint64_t bad_counter = 0;
  std::uint64_t wrong_source = 0;  // commands from another source address
  std::uint64_t ignored = 0;       // other PGNs, lockstep frames in realtime
  std::uint64_t sent = 0;
  std::uint64_t send_failed = 0;
  std::uint64_t rejected() const { return bad_checksum + bad_counter + wrong_source; }
};

class CanNode {
 public:
  static drivers::LinkResult<std::unique_ptr<CanNode>> open(const drivers::LinkUri& endpoint,
                                                            Governor& governor, ClockMode clock,
                                                            CanNodeOptions options = {});
  ~CanNode();
  void start();
  void stop();  // joins; idempotent
  std::string endpoint() const { return endpoint_; }
  std::optional<drivers::LinkError> failure() const;
  CanCounters counters() const;

  // Acts on one received frame (public for tests that feed frames directly).
  void handle(const can_frame& frame);

 private:
  struct PendingEcho {
    std::uint8_t counter = 0;
    double received_pct = 0.0;
  };
  CanNode(std::unique_ptr<drivers::can::CanEndpoint> ep, Governor& governor, ClockMode clock,
          CanNodeOptions options, std::string endpoint);
  void run();
  bool from_rig(const can_frame& frame);
  void on_tick(const GovernorSnapshot& s);  // called by the governor with its lock held
  void send_echoes_locked(const GovernorSnapshot& s);
  void send_sample_locked(const GovernorSnapshot& s);
  void send_locked(const can_frame& frame);
  void handle_command(const can_frame& frame);
  void handle_tsc1(const can_frame& frame);
  void handle_lockstep(const can_frame& frame);
  void command_accepted(std::uint8_t counter, double received_pct);

  std::unique_ptr<drivers::can::CanEndpoint> ep_;
  Governor& governor_;
  ClockMode clock_;
  CanNodeOptions options_;
  std::string endpoint_;
  double synchronous_rpm_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mu_;  // guards ep_, counters_, failure_ and the state below
  CanCounters counters_;
  std::optional<drivers::LinkError> failure_;
  std::optional<std::uint8_t> command_counter_;
  std::optional<std::uint8_t> tsc1_counter_;
  std::vector<PendingEcho> pending_echoes_;  // commands accepted since the last tick
};

}  // namespace plantsim::serve
