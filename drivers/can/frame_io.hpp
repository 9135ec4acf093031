// CAN frame I/O on a file descriptor: one `struct can_frame` per read/write, as on a
// SocketCAN raw socket. The same calls serve a UDP datagram socket (can+udp) and an
// AF_UNIX SOCK_SEQPACKET socketpair (tests). Thin and fail-fast, like can-utils: the caller
// owns the fd; these functions never throw and turn errno into a LinkError naming `where`.
#pragma once

#include <linux/can.h>
#include <sys/socket.h>

#include <chrono>
#include <string_view>

#include "drivers/governor_link.hpp"

namespace drivers::can {

// Sends one frame (to `to` when given, e.g. an unconnected UDP socket).
LinkResult<void> write_frame(int fd, const can_frame& frame, std::string_view where,
                             const sockaddr* to = nullptr, socklen_t to_len = 0);

// Waits up to `timeout` for one frame. kTimeout when none arrives, kLinkLost when the peer
// closed or the socket failed, kProtocol when the datagram is not a struct can_frame.
// `from`/`from_len` receive the sender's address when given.
LinkResult<can_frame> read_frame(int fd, std::chrono::milliseconds timeout, std::string_view where,
                                 sockaddr_storage* from = nullptr, socklen_t* from_len = nullptr);

// errno of a failed socket call -> LinkError (kLinkLost, kTimeout or kUnavailable).
LinkError os_error(int err, std::string_view where, std::string_view call);

}  // namespace drivers::can
