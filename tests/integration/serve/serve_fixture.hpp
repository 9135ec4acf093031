// Shared helpers for the serve integration tests: start a plantsim program, connect a
// libmodbus client, and the scripted lockstep exchange used by several tests.
#pragma once

#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "drivers/governor_link.hpp"
#include "drivers/modbus/register_map.hpp"
#include "tests/integration/serve/child_process.hpp"

namespace plantsim::testing {

using namespace std::chrono_literals;

// The linear test plant program (protocol tests) and the real plant program.
inline std::string linear_program() { return tests_bin_path("plantsim_linear"); }
inline std::string real_program() { return bin_path("plantsim"); }
inline bool real_program_exists() { return std::filesystem::exists(real_program()); }

struct Served {
  std::unique_ptr<ChildProcess> process;
  int modbus_port = -1;
  int can_port = -1;
};

// Starts `program` with `args`, waits for the ready lines of the endpoints it was given.
inline Served start_served(const std::string& program, std::vector<std::string> args,
                           bool modbus = true, bool can = false) {
  Served s;
  args.insert(args.begin(), program);
  s.process = std::make_unique<ChildProcess>(args);
  for (int i = 0; i < (modbus ? 1 : 0) + (can ? 1 : 0); ++i) {
    auto line = s.process->wait_for_line(" ready", 20s);
    if (!line) {
      ADD_FAILURE() << program << " did not report ready: " << s.process->stderr_text(1s);
      return s;
    }
    if (line->find("plantsim: modbus") == 0) s.modbus_port = port_of_ready_line(*line);
    if (line->find("plantsim: can") == 0) s.can_port = port_of_ready_line(*line);
  }
  return s;
}

struct ModbusDeleter {
  void operator()(modbus_t* ctx) const {
    modbus_close(ctx);
    modbus_free(ctx);
  }
};
using ModbusClient = std::unique_ptr<modbus_t, ModbusDeleter>;

inline ModbusClient connect_tcp(int port) {
  ModbusClient ctx(modbus_new_tcp("127.0.0.1", port));
  if (!ctx || modbus_connect(ctx.get()) != 0) return nullptr;
  modbus_set_slave(ctx.get(), drivers::modbus_map::kDefaultUnit);
  modbus_set_response_timeout(ctx.get(), 2, 0);
  return ctx;
}

inline std::array<std::uint16_t, 10> read_inputs(modbus_t* ctx) {
  std::array<std::uint16_t, 10> regs{};
  EXPECT_EQ(modbus_read_input_registers(ctx, 0, 10, regs.data()), 10) << modbus_strerror(errno);
  return regs;
}

inline std::int32_t power_w_of(const std::array<std::uint16_t, 10>& r) {
  return static_cast<std::int32_t>((static_cast<std::uint32_t>(r[0]) << 16) | r[1]);
}
inline std::int16_t bias_echo_of(const std::array<std::uint16_t, 10>& r) {
  return static_cast<std::int16_t>(r[drivers::modbus_map::kInBiasEcho]);
}
inline std::uint32_t time_ms_of(const std::array<std::uint16_t, 10>& r) {
  return (static_cast<std::uint32_t>(r[7]) << 16) | r[8];
}

// One rig cycle: bias (0.001 %), heartbeat and enable in one write of holding 0-2.
inline void write_command(modbus_t* ctx, std::int16_t bias, std::uint16_t heartbeat,
                          bool enable = true) {
  const std::uint16_t regs[3] = {static_cast<std::uint16_t>(bias), heartbeat,
                                 static_cast<std::uint16_t>(enable ? 1 : 0)};
  EXPECT_EQ(modbus_write_registers(ctx, 0, 3, regs), 3) << modbus_strerror(errno);
}

inline void advance(modbus_t* ctx, std::uint16_t ticks) {
  EXPECT_EQ(modbus_write_register(ctx, drivers::modbus_map::kHoldLockstepTicks, ticks), 1)
      << modbus_strerror(errno);
}

// A scripted lockstep exchange at 100 Hz (10 ticks of 1 ms per exchange): a bias sequence
// of steps and a ramp, the heartbeat incremented every write. Returns every input register
// read, in order, as the bytes a rig would record.
inline std::vector<std::uint16_t> scripted_exchange(modbus_t* ctx, int exchanges) {
  std::vector<std::uint16_t> out;
  for (int k = 0; k < exchanges; ++k) {
    const auto bias = static_cast<std::int16_t>(k < 50 ? 0 : (k < 150 ? 1000 : 2000 - 5 * k));
    write_command(ctx, bias, static_cast<std::uint16_t>(k + 1));
    advance(ctx, 10);
    const auto r = read_inputs(ctx);
    out.insert(out.end(), r.begin(), r.end());
  }
  return out;
}

// Starts `program` in lockstep over Modbus TCP with `seed`, runs the scripted exchange (300
// exchanges) against it and returns the recorded input registers; empty when the connection
// failed (already reported as a test failure).
inline std::vector<std::uint16_t> lockstep_recording(const std::string& program,
                                                     const std::string& seed) {
  auto s = start_served(program,
                        {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep", "--seed", seed});
  auto ctx = connect_tcp(s.modbus_port);
  EXPECT_TRUE(ctx);
  return ctx ? scripted_exchange(ctx.get(), 300) : std::vector<std::uint16_t>{};
}

// Runs a program to its exit (10 s at most) and collects its output.
struct Outcome {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline Outcome run_to_end(std::vector<std::string> args,
                          const std::string& program = linear_program()) {
  args.insert(args.begin(), program);
  ChildProcess p(args);
  Outcome o;
  const auto code = p.wait(10s);
  EXPECT_TRUE(code) << "did not exit";
  o.exit_code = code.value_or(-1);
  while (auto line = p.read_line(10ms)) o.out += *line + "\n";
  o.err = p.stderr_text(100ms);
  return o;
}

}  // namespace plantsim::testing
