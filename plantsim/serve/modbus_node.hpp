// The governor's Modbus face (DESIGN.md section 6 map, drivers/modbus/register_map.hpp):
// a drivers::ModbusServer on its own thread that turns holding-register writes into governor
// commands and refreshes the input registers from the latest tick before every answer.
//
// Lockstep: a write of N to holding 100 advances the plant exactly N ticks *before* that
// write is answered, so the rig's next read sees the plant N ticks on. In realtime the
// register is stored but does nothing (the clock thread ticks the plant).
//
// serve.drop_link: after the request that carried plant time past the drop (lockstep), or
// within one 50 ms poll of it (realtime), the listener and every connection are closed.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "drivers/modbus/modbus_server.hpp"
#include "plantsim/serve/endpoint.hpp"
#include "plantsim/serve/governor.hpp"

namespace plantsim::serve {

enum class ClockMode { kRealtime, kLockstep };

// Input registers 0-9 from a snapshot (power int32 W high word first, speed 0.1 rpm,
// frequency 0.001 Hz, voltage 1 V, bias echo int16 0.001 %, status, plant time uint32 ms high
// word first, sample counter = ticks mod 2^16 unless frozen). Values outside a register's range
// saturate; power "not available" (serve.nan_power or non-finite) is INT32_MIN.
void encode_input_registers(const GovernorSnapshot& s, std::uint16_t* regs);

class ModbusNode {
 public:
  // Opens (binds / opens the device); errors name the endpoint. Does not start serving.
  static drivers::LinkResult<std::unique_ptr<ModbusNode>> open(const drivers::LinkUri& endpoint,
                                                               Governor& governor, ClockMode clock);
  ~ModbusNode();
  void start();
  void stop();  // joins the thread; idempotent
  std::string endpoint() const { return endpoint_; }
  // Set when the transport itself failed (device gone); the thread has then stopped.
  std::optional<drivers::LinkError> failure() const;
  drivers::ModbusServerCounters counters() const;

 private:
  ModbusNode(std::unique_ptr<drivers::ModbusServer> server, Governor& governor, ClockMode clock);
  void run();
  void on_request(const drivers::ModbusRequest& request, modbus_mapping_t& map);

  std::unique_ptr<drivers::ModbusServer> server_;  // reset when serve.drop_link takes effect
  std::string endpoint_;
  Governor& governor_;
  ClockMode clock_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mu_;  // guards failure_ and counters_
  std::optional<drivers::LinkError> failure_;
  drivers::ModbusServerCounters counters_;
};

}  // namespace plantsim::serve
