#include "modbus_test_server.hpp"

#include <modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <stdexcept>

#include "drivers/modbus/register_map.hpp"

namespace drivers::testing {

namespace map = modbus_map;

ModbusTestServer::ModbusTestServer(bool lockstep, int input_count)
    : lockstep_(lockstep), input_count_(input_count) {
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", 0);
  ctx_ = ctx;
  mapping_ = modbus_mapping_new(0, 0, map::kHoldingCount, input_count);
  listen_fd_ = modbus_tcp_listen(ctx, 1);
  if (!ctx || !mapping_ || listen_fd_ < 0) throw std::runtime_error("test server setup failed");
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  modbus_set_indication_timeout(ctx, 0, 20000);  // wake up to notice stop_
  thread_ = std::thread([this] { run(); });
}

ModbusTestServer::ModbusTestServer(const std::string& rtu_device, int baud)
    : lockstep_(true), input_count_(map::kInputCount) {
  modbus_t* ctx = modbus_new_rtu(rtu_device.c_str(), baud, 'N', 8, 1);
  ctx_ = ctx;
  mapping_ = modbus_mapping_new(0, 0, map::kHoldingCount, map::kInputCount);
  if (!ctx || !mapping_ || modbus_set_slave(ctx, map::kDefaultUnit) != 0 ||
      modbus_connect(ctx) != 0) {
    throw std::runtime_error("RTU test server setup failed on " + rtu_device);
  }
  modbus_set_indication_timeout(ctx, 0, 20000);
  thread_ = std::thread([this] { serve_client(); });
}

ModbusTestServer::~ModbusTestServer() {
  stop_ = true;
  thread_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  modbus_mapping_free(static_cast<modbus_mapping_t*>(mapping_));
  modbus_close(static_cast<modbus_t*>(ctx_));
  modbus_free(static_cast<modbus_t*>(ctx_));
}

std::vector<ModbusTestServer::Write> ModbusTestServer::writes() const {
  std::lock_guard lock(mutex_);
  return writes_;
}

void ModbusTestServer::run() {
  auto* ctx = static_cast<modbus_t*>(ctx_);
  while (!stop_) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 20) <= 0) continue;
    int fd = listen_fd_;
    if (modbus_tcp_accept(ctx, &fd) < 0) continue;
    serve_client();
    modbus_close(ctx);  // closes the client socket only
  }
}

void ModbusTestServer::serve_client() {
  auto* ctx = static_cast<modbus_t*>(ctx_);
  auto* mb = static_cast<modbus_mapping_t*>(mapping_);
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  while (!stop_) {
    const int rc = modbus_receive(ctx, query);
    if (rc < 0 && errno == ETIMEDOUT) continue;
    if (rc < 0 && listen_fd_ < 0) {  // RTU: a garbled frame, keep listening
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    if (rc < 0) return;  // TCP: client closed
    if (rc == 0) continue;
    if (close_after_requests == 0) return;  // link loss: drop the connection unanswered
    if (close_after_requests > 0) --close_after_requests;
    if (reply_delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(reply_delay_ms));
    apply_writes(query);
    fill_inputs(query);
    modbus_reply(ctx, query, rc, mb);
  }
}

// Applies a write before the reply (so the plant has advanced and the write is recorded by
// the time the client sees the answer, as in DESIGN.md section 6 lockstep).
void ModbusTestServer::apply_writes(const std::uint8_t* query) {
  auto* mb = static_cast<modbus_mapping_t*>(mapping_);
  const int hl = modbus_get_header_length(static_cast<modbus_t*>(ctx_));
  const int function = query[hl];
  const int address = (query[hl + 1] << 8) | query[hl + 2];
  if (function != 0x06 && function != 0x10) return;
  const int count = function == 0x06 ? 1 : ((query[hl + 3] << 8) | query[hl + 4]);
  const std::uint8_t* data = function == 0x06 ? &query[hl + 3] : &query[hl + 6];
  std::uint16_t hold[3] = {mb->tab_registers[0], mb->tab_registers[1], mb->tab_registers[2]};
  for (int i = 0; i < count && address + i < 3; ++i) {
    hold[address + i] = static_cast<std::uint16_t>((data[2 * i] << 8) | data[2 * i + 1]);
  }
  if (address == map::kHoldLockstepTicks && !freeze_counter) {
    counter_ = static_cast<std::uint16_t>(counter_ + ((data[0] << 8) | data[1]));
  }
  if (address == map::kHoldBias) {
    std::lock_guard lock(mutex_);
    writes_.push_back({static_cast<std::int16_t>(hold[0]), hold[1], hold[2]});
  }
}

// Fills the input registers before a reply, from the holding registers and the counter.
void ModbusTestServer::fill_inputs(const std::uint8_t* query) {
  auto* ctx = static_cast<modbus_t*>(ctx_);
  auto* mb = static_cast<modbus_mapping_t*>(mapping_);
  const int hl = modbus_get_header_length(ctx);
  if (query[hl] != 0x04 || input_count_ < map::kInputCount) return;
  if (!lockstep_ && !freeze_counter) ++counter_;
  const std::uint16_t* hold = mb->tab_registers;
  const bool enabled = hold[map::kHoldControl] & map::kControlEnableBias;
  const auto bias_raw = static_cast<std::int16_t>(enabled ? hold[map::kHoldBias] : 0);
  const auto power_w =
      static_cast<std::int32_t>(kBasePowerW + bias_raw * map::kBiasPctPerBit * kWattsPerPct);
  const auto p = static_cast<std::uint32_t>(power_w);
  const std::uint32_t time_ms = counter_;  // 1 ms tick
  std::uint16_t* in = mb->tab_input_registers;
  in[map::kInPowerHi] = static_cast<std::uint16_t>(p >> 16);
  in[map::kInPowerLo] = static_cast<std::uint16_t>(p & 0xFFFF);
  in[map::kInSpeed] = 6000;
  in[map::kInFreq] = 50000;
  in[map::kInVoltage] = 11000;
  in[map::kInBiasEcho] = static_cast<std::uint16_t>(bias_raw);
  in[map::kInStatus] = 0x3 | (enabled ? 0x4 : 0);
  in[map::kInTimeHi] = static_cast<std::uint16_t>(time_ms >> 16);
  in[map::kInTimeLo] = static_cast<std::uint16_t>(time_ms & 0xFFFF);
  in[map::kInCounter] = counter_;
}

}  // namespace drivers::testing
