#include "drivers/can/transport.hpp"

#include <linux/can/raw.h>
#include <net/if.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "drivers/can/frame_io.hpp"

namespace drivers::can {
namespace {

// Owns a file descriptor.
class Fd {
 public:
  explicit Fd(int fd = -1) : fd_(fd) {}
  Fd(Fd&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  Fd& operator=(Fd&&) = delete;
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }

 private:
  int fd_;
};

class UdpEndpoint final : public CanEndpoint {
 public:
  UdpEndpoint(Fd fd, CanRole role, std::string where, int port)
      : fd_(std::move(fd)), role_(role), where_(std::move(where)), port_(port) {}

  LinkResult<void> send(const can_frame& frame) override {
    if (role_ == CanRole::kClient) return write_frame(fd_.get(), frame, where_);
    if (!peer_len_) {
      return LinkError{LinkErrorKind::kLinkLost, where_,
                       "no peer yet (the node answers the last sender)"};
    }
    return write_frame(fd_.get(), frame, where_, reinterpret_cast<const sockaddr*>(&peer_),
                       peer_len_);
  }

  LinkResult<can_frame> receive(std::chrono::milliseconds timeout) override {
    if (role_ == CanRole::kClient) return read_frame(fd_.get(), timeout, where_);
    sockaddr_storage from{};
    socklen_t len = 0;
    auto r = read_frame(fd_.get(), timeout, where_, &from, &len);
    if (r) {
      peer_ = from;
      peer_len_ = len;
    }
    return r;
  }

  bool has_peer() const override { return role_ == CanRole::kClient || peer_len_ != 0; }
  int local_port() const override { return port_; }
  int fd() const override { return fd_.get(); }
  std::string describe() const override { return where_; }

 private:
  Fd fd_;
  CanRole role_;
  std::string where_;
  int port_;
  sockaddr_storage peer_{};
  socklen_t peer_len_ = 0;
};

class SocketcanEndpoint final : public CanEndpoint {
 public:
  SocketcanEndpoint(Fd fd, std::string where) : fd_(std::move(fd)), where_(std::move(where)) {}
  LinkResult<void> send(const can_frame& frame) override {
    return write_frame(fd_.get(), frame, where_);
  }
  LinkResult<can_frame> receive(std::chrono::milliseconds timeout) override {
    return read_frame(fd_.get(), timeout, where_);
  }
  bool has_peer() const override { return true; }
  int local_port() const override { return 0; }
  int fd() const override { return fd_.get(); }
  std::string describe() const override { return where_; }

 private:
  Fd fd_;
  std::string where_;
};

LinkError unavailable(const std::string& where, const char* call, int err) {
  return LinkError{
      LinkErrorKind::kUnavailable, where,
      std::string("CAN unavailable on this host (") + call + ": " + std::strerror(err) + ")"};
}

LinkResult<sockaddr_in> resolve_ipv4(const LinkUri& uri, const std::string& where) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  const std::string port = std::to_string(uri.port);
  if (const int rc = ::getaddrinfo(uri.host.c_str(), port.c_str(), &hints, &res); rc != 0) {
    return LinkError{LinkErrorKind::kConfig, where,
                     "cannot resolve host '" + uri.host + "': " + ::gai_strerror(rc)};
  }
  sockaddr_in addr{};
  std::memcpy(&addr, res->ai_addr, sizeof addr);
  ::freeaddrinfo(res);
  return addr;
}

LinkResult<std::unique_ptr<CanEndpoint>> open_udp(const LinkUri& uri, CanRole role) {
  const std::string where = uri.text;
  auto node = resolve_ipv4(uri, where);
  if (!node) return node.error();
  Fd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  if (fd.get() < 0) return os_error(errno, where, "socket(AF_INET, SOCK_DGRAM)");
  const sockaddr_in& node_addr = node.value();
  if (role == CanRole::kNode) {
    if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&node_addr), sizeof node_addr) != 0) {
      return os_error(errno, where, "bind");
    }
  } else {
    // Ephemeral local port; connect() so that only the node's datagrams are accepted and an
    // absent node shows up as ECONNREFUSED (link lost) instead of silence.
    if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&node_addr), sizeof node_addr) != 0) {
      return os_error(errno, where, "connect");
    }
  }
  sockaddr_in local{};
  socklen_t len = sizeof local;
  if (::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&local), &len) != 0) {
    return os_error(errno, where, "getsockname");
  }
  std::unique_ptr<CanEndpoint> ep =
      std::make_unique<UdpEndpoint>(std::move(fd), role, where, ntohs(local.sin_port));
  return ep;
}

}  // namespace

LinkResult<std::unique_ptr<CanEndpoint>> open_socketcan(const std::string& interface) {
  const std::string where = "can+socketcan:" + interface;
  if (interface.size() >= IFNAMSIZ) {
    return LinkError{LinkErrorKind::kConfig, where,
                     "interface name longer than " + std::to_string(IFNAMSIZ - 1)};
  }
  Fd fd(::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW));
  if (fd.get() < 0) {
    const int err = errno;
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
      return unavailable(where, "socket(PF_CAN, SOCK_RAW, CAN_RAW)", err);
    }
    return os_error(err, where, "socket(PF_CAN)");
  }
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, interface.c_str(), interface.size() + 1);
  if (::ioctl(fd.get(), SIOCGIFINDEX, &ifr) != 0) {
    const int err = errno;
    if (err == ENODEV) return unavailable(where, ("interface " + interface).c_str(), err);
    return os_error(err, where, "ioctl(SIOCGIFINDEX)");
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    return os_error(errno, where, "bind");
  }
  std::unique_ptr<CanEndpoint> ep = std::make_unique<SocketcanEndpoint>(std::move(fd), where);
  return ep;
}

LinkResult<std::unique_ptr<CanEndpoint>> open_can_endpoint(const LinkUri& uri, CanRole role) {
  switch (uri.scheme) {
    case LinkScheme::kCanUdp:
      return open_udp(uri, role);
    case LinkScheme::kCanSocketcan:
      return open_socketcan(uri.device);
    default:
      return LinkError{LinkErrorKind::kConfig, uri.text, "expected a can+udp or can+socketcan URI"};
  }
}

}  // namespace drivers::can
