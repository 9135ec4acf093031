// The governor's CAN face (DESIGN.md section 6 CAN map, drivers/can/j1939.hpp) over the
// drivers' can+udp or SocketCAN endpoint, node role.
//
// Received:
//   PGN 0xFF50  bias, enable, 4-bit counter + checksum. The counter is the heartbeat. A frame
//               with a bad checksum is ignored and counted; a frame whose counter is not the
//               previous + 1 (mod 16) is ignored and counted, and the counter is re-synchronised
//               to it, so a restarted rig is accepted again from its second frame.
//   TSC1        speed request, for governors that only take TSC1. In DEGOV1 the speed error
//               and the bias enter the same summing junction in per unit, so a speed request n
//               is the bias 100 (n - n0) / n0 % with n0 the synchronous speed at start
//               (0.125 rpm/bit is 0.021 % at 600 rpm: coarse, as the rig warns).
//   PGN 0xFF52  lockstep: advance exactly N ticks (one 0xFF51 per tick) before the next frame
//               is read. Ignored in realtime.
// Sent (plant time): PGN 0xFF51 every tick, EEC1 every 20 ms, GTACP every 100 ms. Over UDP
// nothing is sent until the rig's first frame names the peer.
#pragma once

#include <linux/can.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "drivers/can/transport.hpp"
#include "plantsim/serve/governor.hpp"
#include "plantsim/serve/modbus_node.hpp"

namespace plantsim::serve {

struct CanCounters {
  std::uint64_t received = 0;
  std::uint64_t accepted = 0;      // commands, TSC1 and lockstep frames acted on
  std::uint64_t bad_checksum = 0;  // also malformed frames of a known PGN
  std::uint64_t bad_counter = 0;
  std::uint64_t ignored = 0;  // other PGNs, lockstep frames in realtime
  std::uint64_t sent = 0;
  std::uint64_t send_failed = 0;
  std::uint64_t rejected() const { return bad_checksum + bad_counter; }
};

class CanNode {
 public:
  static drivers::LinkResult<std::unique_ptr<CanNode>> open(const drivers::LinkUri& endpoint,
                                                            Governor& governor, ClockMode clock);
  ~CanNode();
  void start();
  void stop();  // joins; idempotent
  std::string endpoint() const { return endpoint_; }
  std::optional<drivers::LinkError> failure() const;
  CanCounters counters() const;

  // Acts on one received frame (public for tests that feed frames directly).
  void handle(const can_frame& frame);

 private:
  CanNode(std::unique_ptr<drivers::can::CanEndpoint> ep, Governor& governor, ClockMode clock,
          std::string endpoint);
  void run();
  void on_tick(const GovernorSnapshot& s);  // called by the governor with its lock held
  void send_locked(const can_frame& frame);
  void handle_command(const can_frame& frame);
  void handle_tsc1(const can_frame& frame);

  std::unique_ptr<drivers::can::CanEndpoint> ep_;
  Governor& governor_;
  ClockMode clock_;
  std::string endpoint_;
  double synchronous_rpm_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mu_;  // guards ep_, counters_, failure_ and the counters below
  CanCounters counters_;
  std::optional<drivers::LinkError> failure_;
  std::optional<std::uint8_t> command_counter_;
  std::optional<std::uint8_t> tsc1_counter_;
};

}  // namespace plantsim::serve
