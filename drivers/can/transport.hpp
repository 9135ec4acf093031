// CAN transports of DESIGN.md section 6, behind one small endpoint API used by both the rig
// (client role) and plantsim's CAN node (node role):
//   can+udp        one struct can_frame per UDP datagram. The node binds host:port (port 0:
//                  ephemeral, see local_port()) and answers to the last peer it heard from;
//                  the client binds an ephemeral port and sends to the node.
//   can+socketcan  socket(PF_CAN, SOCK_RAW, CAN_RAW) bound to the interface; both roles are
//                  the same. On a kernel without CAN (EAFNOSUPPORT, EPROTONOSUPPORT) or
//                  without the interface (ENODEV) opening fails with kUnavailable
//                  "CAN unavailable on this host".
#pragma once

#include <linux/can.h>

#include <chrono>
#include <memory>
#include <string>

#include "drivers/governor_link.hpp"
#include "drivers/link_uri.hpp"

namespace drivers::can {

enum class CanRole { kClient, kNode };

class CanEndpoint {
 public:
  virtual ~CanEndpoint() = default;
  // Node role over UDP: kLinkLost "no peer yet" until a frame has been received.
  virtual LinkResult<void> send(const can_frame& frame) = 0;
  // Waits up to `timeout` (0: poll once) for the next frame.
  virtual LinkResult<can_frame> receive(std::chrono::milliseconds timeout) = 0;
  virtual bool has_peer() const = 0;         // always true except a UDP node not yet contacted
  virtual int local_port() const = 0;        // bound UDP port (0 for SocketCAN)
  virtual int fd() const = 0;                // for poll() in a server loop
  virtual std::string describe() const = 0;  // e.g. "can+udp://127.0.0.1:29536"
};

// Opens a can+udp or can+socketcan endpoint; kConfig for a non-CAN URI.
LinkResult<std::unique_ptr<CanEndpoint>> open_can_endpoint(const LinkUri& uri, CanRole role);

// Socket setup alone, for tests and diagnostics: kUnavailable when the host has no CAN.
LinkResult<std::unique_ptr<CanEndpoint>> open_socketcan(const std::string& interface);

}  // namespace drivers::can
