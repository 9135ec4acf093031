#include "drivers/can/frame_io.hpp"

#include <poll.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace drivers::can {

LinkError os_error(int err, std::string_view where, std::string_view call) {
  LinkErrorKind kind = LinkErrorKind::kLinkLost;
  switch (err) {
    case EAGAIN:
    case ENOBUFS:  // SocketCAN: transmit queue full, the bus is not taking frames
      kind = LinkErrorKind::kTimeout;
      break;
    case EAFNOSUPPORT:
    case EPROTONOSUPPORT:
    case ENODEV:
      kind = LinkErrorKind::kUnavailable;
      break;
    default:
      break;
  }
  return LinkError{kind, std::string(where), std::string(call) + ": " + std::strerror(err)};
}

LinkResult<void> write_frame(int fd, const can_frame& frame, std::string_view where,
                             const sockaddr* to, socklen_t to_len) {
  for (;;) {
    const ssize_t n = to ? ::sendto(fd, &frame, sizeof frame, MSG_NOSIGNAL, to, to_len)
                         : ::send(fd, &frame, sizeof frame, MSG_NOSIGNAL);
    if (n == static_cast<ssize_t>(sizeof frame)) return {};
    if (n >= 0) {
      return LinkError{LinkErrorKind::kProtocol, std::string(where),
                       "short write of " + std::to_string(n) + " bytes"};
    }
    if (errno != EINTR) return os_error(errno, where, "send");
  }
}

LinkResult<can_frame> read_frame(int fd, std::chrono::milliseconds timeout, std::string_view where,
                                 sockaddr_storage* from, socklen_t* from_len) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    // Round up so that a short timeout still waits rather than polling once.
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, left.count() > 0 ? static_cast<int>(left.count()) : 0);
    if (ready < 0) {
      if (errno == EINTR) continue;
      return os_error(errno, where, "poll");
    }
    if (ready == 0) {
      return LinkError{LinkErrorKind::kTimeout, std::string(where),
                       "no frame within " + std::to_string(timeout.count()) + " ms"};
    }
    can_frame frame{};
    socklen_t len = from ? static_cast<socklen_t>(sizeof *from) : 0;
    const ssize_t n = ::recvfrom(fd, &frame, sizeof frame, MSG_TRUNC,
                                 reinterpret_cast<sockaddr*>(from), from ? &len : nullptr);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      return os_error(errno, where, "recv");
    }
    if (from_len) *from_len = len;
    if (n == 0 && (p.revents & POLLHUP)) {
      return LinkError{LinkErrorKind::kLinkLost, std::string(where), "peer closed the link"};
    }
    if (n != static_cast<ssize_t>(sizeof frame)) {
      return LinkError{LinkErrorKind::kProtocol, std::string(where),
                       "expected a " + std::to_string(sizeof frame) +
                           "-byte struct can_frame, got " + std::to_string(n) + " bytes"};
    }
    return frame;
  }
}

}  // namespace drivers::can
