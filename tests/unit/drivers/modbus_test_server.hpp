// A minimal Modbus TCP server on 127.0.0.1 (real libmodbus, ephemeral port) implementing the
// register map of drivers/modbus/register_map.hpp, with deliberate misbehaviour for the
// client's error paths: slow replies, a frozen counter, too few input registers (illegal
// address), and closing the connection after N requests.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace drivers::testing {

class ModbusTestServer {
 public:
  // lockstep: the counter moves only on writes to holding 100; otherwise +1 per read.
  explicit ModbusTestServer(bool lockstep, int input_count = 10);
  // Modbus RTU server (lockstep, unit 1) on a serial device, e.g. one end of a socat pty pair.
  ModbusTestServer(const std::string& rtu_device, int baud);
  ~ModbusTestServer();
  int port() const { return port_; }

  struct Write {
    std::int16_t bias_raw;
    std::uint16_t heartbeat;
    std::uint16_t control;
  };
  std::vector<Write> writes() const;  // holding 0..2 after every write touching holding 0

  std::atomic<int> reply_delay_ms{0};
  std::atomic<bool> freeze_counter{false};
  std::atomic<int> close_after_requests{-1};  // -1: never

  // Plant response used for the input registers: P = 3.5 MW + bias * 46 kW/%.
  static constexpr double kBasePowerW = 3.5e6;
  static constexpr double kWattsPerPct = 46.0e3;

 private:
  void run();
  void serve_client();
  void apply_writes(const std::uint8_t* query);
  void fill_inputs(const std::uint8_t* query);

  bool lockstep_;
  int input_count_;
  int port_ = 0;
  int listen_fd_ = -1;
  void* ctx_ = nullptr;      // modbus_t*
  void* mapping_ = nullptr;  // modbus_mapping_t*
  std::uint16_t counter_ = 0;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::vector<Write> writes_;
  std::thread thread_;
};

}  // namespace drivers::testing
