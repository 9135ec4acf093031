#include "drivers/modbus/modbus_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace drivers {
namespace {

constexpr int kMbapLength = 7;  // transaction id, protocol id, length, unit id
constexpr int kMaxPduLength = 253;

std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }

LinkError os_error(LinkErrorKind kind, std::string where, int err) {
  return LinkError{kind, std::move(where), modbus_strerror(err)};
}

timeval to_timeval(std::chrono::milliseconds timeout) {
  const auto ms = std::max<std::int64_t>(0, timeout.count());
  return timeval{static_cast<time_t>(ms / 1000), static_cast<suseconds_t>((ms % 1000) * 1000)};
}

}  // namespace

ModbusRequest decode_request(const std::uint8_t* buffer, int length, int header_length,
                             int holding_count) {
  ModbusRequest r;
  const std::uint8_t* pdu = buffer + header_length;
  r.unit = buffer[header_length - 1];
  r.function = pdu[0];
  r.address = be16(pdu + 1);
  int count = 0;
  int values_at = 0;
  switch (r.function) {
    case MODBUS_FC_WRITE_SINGLE_REGISTER:
      r.write_address = r.address;
      count = 1;
      values_at = 3;
      break;
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS:
      r.write_address = r.address;
      count = be16(pdu + 3);
      values_at = 6;
      break;
    default:
      return r;
  }
  // Only take values that are really in the frame; libmodbus answers a short frame's
  // out-of-range count with an exception, and then nothing must be acted on.
  const int available = (length - header_length - values_at) / 2;
  if (count < 1 || count > 123 || count > available) return r;
  r.values.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) r.values[i] = be16(pdu + values_at + 2 * i);
  r.write_in_range = r.write_address + count <= holding_count;
  return r;
}

bool ModbusServerOptions::serves(int function) const {
  return std::find(functions.begin(), functions.end(), function) != functions.end();
}

ModbusServer::ModbusServer(modbus_t* ctx, modbus_mapping_t* mapping, ModbusServerOptions options)
    : ctx_(ctx), mapping_(mapping), options_(options) {}

ModbusServer::~ModbusServer() {
  for (auto& c : clients_) ::close(c.fd);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  if (ctx_ != nullptr) {
    if (rtu_) modbus_close(ctx_);
    modbus_free(ctx_);
  }
  if (mapping_ != nullptr) modbus_mapping_free(mapping_);
}

LinkResult<std::unique_ptr<ModbusServer>> ModbusServer::listen_tcp(
    const std::string& host_in, int port, const ModbusServerOptions& options) {
  const std::string where = fmt::format("tcp://{}:{}", host_in, port);
  const std::string host = host_in == "localhost" ? "127.0.0.1" : host_in;
  in_addr probe{};
  if (port < 0 || port > 65535 || inet_pton(AF_INET, host.c_str(), &probe) != 1) {
    return LinkError{LinkErrorKind::kConfig, where, "expected an IPv4 address and a port 0-65535"};
  }
  modbus_t* ctx = modbus_new_tcp(host.c_str(), port);
  if (ctx == nullptr) return os_error(LinkErrorKind::kConfig, where, errno);
  modbus_mapping_t* map = modbus_mapping_new(0, 0, options.holding_count, options.input_count);
  std::unique_ptr<ModbusServer> server(new ModbusServer(ctx, map, options));
  if (map == nullptr) return os_error(LinkErrorKind::kConfig, where, errno);
  modbus_set_debug(ctx, options.debug ? TRUE : FALSE);
  server->listen_fd_ = modbus_tcp_listen(ctx, options.max_clients);
  if (server->listen_fd_ < 0) {
    const int err = errno;
    return LinkError{LinkErrorKind::kUnavailable, where,
                     fmt::format("cannot listen: {}", std::strerror(err))};
  }
  sockaddr_in bound{};
  socklen_t len = sizeof bound;
  getsockname(server->listen_fd_, reinterpret_cast<sockaddr*>(&bound), &len);
  server->port_ = ntohs(bound.sin_port);
  server->host_ = host;
  return server;
}

LinkResult<std::unique_ptr<ModbusServer>> ModbusServer::open_rtu(
    const std::string& device, int baud, char parity, int data_bits, int stop_bits,
    const ModbusServerOptions& options) {
  const std::string where = fmt::format("rtu:{}", device);
  modbus_t* ctx = modbus_new_rtu(device.c_str(), baud, parity, data_bits, stop_bits);
  if (ctx == nullptr) return os_error(LinkErrorKind::kConfig, where, errno);
  modbus_mapping_t* map = modbus_mapping_new(0, 0, options.holding_count, options.input_count);
  std::unique_ptr<ModbusServer> server(new ModbusServer(ctx, map, options));
  if (map == nullptr) return os_error(LinkErrorKind::kConfig, where, errno);
  server->rtu_ = true;
  server->device_ = device;
  server->baud_ = baud;
  modbus_set_debug(ctx, options.debug ? TRUE : FALSE);
  if (modbus_set_slave(ctx, options.unit) != 0) {
    return LinkError{LinkErrorKind::kConfig, where, "unit must be 1-247"};
  }
  if (modbus_connect(ctx) != 0) {
    const int err = errno;
    modbus_free(ctx);  // connect failed: nothing to close
    server->ctx_ = nullptr;
    return LinkError{LinkErrorKind::kUnavailable, where,
                     fmt::format("cannot open serial device: {}", std::strerror(err))};
  }
  // A frame's bytes arrive within a few character times; a stalled half frame is dropped.
  modbus_set_byte_timeout(ctx, 0, 100000);
  modbus_set_indication_timeout(ctx, 0, 100000);
  return server;
}

std::string ModbusServer::endpoint() const {
  if (rtu_) return fmt::format("rtu:{}?baud={}", device_, baud_);
  return fmt::format("tcp://{}:{}", host_, port_);
}

LinkResult<void> ModbusServer::poll(std::chrono::milliseconds timeout, const Hook& before_reply) {
  return rtu_ ? poll_rtu(timeout, before_reply) : poll_tcp(timeout, before_reply);
}

LinkResult<void> ModbusServer::poll_tcp(std::chrono::milliseconds timeout,
                                        const Hook& before_reply) {
  fd_set readable;
  FD_ZERO(&readable);
  FD_SET(listen_fd_, &readable);
  int max_fd = listen_fd_;
  for (const auto& c : clients_) {
    FD_SET(c.fd, &readable);
    max_fd = std::max(max_fd, c.fd);
  }
  timeval tv = to_timeval(timeout);
  const int n = ::select(max_fd + 1, &readable, nullptr, nullptr, &tv);
  if (n < 0) {
    if (errno == EINTR) return {};
    return os_error(LinkErrorKind::kLinkLost, endpoint(), errno);
  }
  if (n == 0) return {};
  // Serve existing clients first (indices stay valid: closing swaps from the back).
  for (std::size_t i = clients_.size(); i-- > 0;) {
    if (FD_ISSET(clients_[i].fd, &readable) && !serve_client(clients_[i], before_reply)) {
      close_client(i);
    }
  }
  if (FD_ISSET(listen_fd_, &readable)) accept_client();
  return {};
}

void ModbusServer::accept_client() {
  const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return;
  if (static_cast<int>(clients_.size()) >= options_.max_clients) {
    ::close(fd);
    ++counters_.refused;
    return;
  }
  ++counters_.connections;
  clients_.push_back(Client{fd, {}});
}

void ModbusServer::close_client(std::size_t index) {
  ::close(clients_[index].fd);
  clients_[index] = std::move(clients_.back());
  clients_.pop_back();
}

bool ModbusServer::serve_client(Client& client, const Hook& before_reply) {
  std::array<std::uint8_t, 1024> chunk{};
  const ssize_t got = ::recv(client.fd, chunk.data(), chunk.size(), 0);
  if (got == 0) return false;  // orderly close
  if (got < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
  client.buffer.insert(client.buffer.end(), chunk.begin(), chunk.begin() + got);
  std::size_t at = 0;
  while (client.buffer.size() - at >= kMbapLength) {
    const std::uint8_t* h = client.buffer.data() + at;
    const int protocol = be16(h + 2);
    const int length = be16(h + 4);  // unit id + PDU
    if (protocol != 0 || length < 2 || length > kMaxPduLength + 1) {
      ++counters_.malformed;
      return false;
    }
    const std::size_t total = 6 + static_cast<std::size_t>(length);
    if (client.buffer.size() - at < total) break;
    std::array<std::uint8_t, MODBUS_MAX_ADU_LENGTH> adu{};
    std::copy_n(h, total, adu.begin());
    modbus_set_socket(ctx_, client.fd);
    answer(adu.data(), static_cast<int>(total), before_reply);
    at += total;
  }
  client.buffer.erase(client.buffer.begin(), client.buffer.begin() + static_cast<long>(at));
  return true;
}

// A failed send shows up as a closed socket (TCP) or is the master's timeout (RTU).
void ModbusServer::answer(const std::uint8_t* adu, int length, const Hook& before_reply) {
  const int header = modbus_get_header_length(ctx_);
  ++counters_.requests;
  if (!options_.serves(adu[header])) {
    if (!(rtu_ && adu[header - 1] == MODBUS_BROADCAST_ADDRESS)) {
      modbus_reply_exception(ctx_, adu, MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
    }
    return;
  }
  const ModbusRequest request = decode_request(adu, length, header, options_.holding_count);
  if (before_reply) before_reply(request, *mapping_);
  modbus_reply(ctx_, adu, length, mapping_);
}

LinkResult<void> ModbusServer::poll_rtu(std::chrono::milliseconds timeout,
                                        const Hook& before_reply) {
  const int fd = modbus_get_socket(ctx_);
  fd_set readable;
  FD_ZERO(&readable);
  FD_SET(fd, &readable);
  timeval tv = to_timeval(timeout);
  const int n = ::select(fd + 1, &readable, nullptr, nullptr, &tv);
  if (n < 0) {
    if (errno == EINTR) return {};
    return os_error(LinkErrorKind::kLinkLost, endpoint(), errno);
  }
  if (n == 0) return {};
  std::array<std::uint8_t, MODBUS_MAX_ADU_LENGTH> adu{};
  const int rc = modbus_receive(ctx_, adu.data());
  if (rc > 0) {
    answer(adu.data(), rc, before_reply);
  } else if (rc < 0) {
    const int err = errno;
    if (err == EBADF || err == EIO || err == ENXIO) {
      return os_error(LinkErrorKind::kLinkLost, endpoint(), err);
    }
    // Bad CRC, truncated frame, noise: drop whatever is buffered and wait for the next frame.
    ++counters_.malformed;
    modbus_flush(ctx_);
  }
  return {};  // rc == 0: a request for another unit on the bus
}

}  // namespace drivers
