#include "tests/bench/serve/lockstep_bench.hpp"

#include <modbus/modbus.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "drivers/can/j1939.hpp"
#include "drivers/can/transport.hpp"
#include "tests/integration/serve/child_process.hpp"

namespace plantsim::bench {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
namespace j1939 = drivers::j1939;

constexpr int kTicksPerExchange = 10;
constexpr double kTickS = 1e-3;

struct Started {
  std::unique_ptr<testing::ChildProcess> process;
  int port = -1;
};

Started start(const std::string& program, std::vector<std::string> args, const char* kind) {
  args.insert(args.begin(), program);
  Started s;
  s.process = std::make_unique<testing::ChildProcess>(args);
  auto line = s.process->wait_for_line(std::string("plantsim: ") + kind, 30s);
  if (!line) throw std::runtime_error(program + " did not start: " + s.process->stderr_text(1s));
  s.port = testing::port_of_ready_line(*line);
  return s;
}

ExchangeFigures figures(std::vector<double>& latencies_us, double wall_s) {
  ExchangeFigures f;
  f.exchanges = static_cast<int>(latencies_us.size());
  f.wall_s = wall_s;
  f.simulated_s = f.exchanges * kTicksPerExchange * kTickS;
  std::sort(latencies_us.begin(), latencies_us.end());
  if (!latencies_us.empty()) {
    f.p50_us = latencies_us[latencies_us.size() / 2];
    f.p99_us = latencies_us[static_cast<std::size_t>(0.99 * (latencies_us.size() - 1))];
  }
  return f;
}

// A bias the rig would send: a 1 % square wave at 1 Hz, so the plant is not idle.
std::int16_t bias_at(int k) { return static_cast<std::int16_t>((k / 50) % 2 == 0 ? 1000 : -1000); }

}  // namespace

ExchangeFigures modbus_lockstep(const std::string& program, const std::vector<std::string>& args,
                                int exchanges) {
  auto all = args;
  all.insert(all.end(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto s = start(program, all, "modbus");
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", s.port);
  if (ctx == nullptr || modbus_connect(ctx) != 0) throw std::runtime_error("connect failed");
  std::vector<double> latencies_us;
  latencies_us.reserve(static_cast<std::size_t>(exchanges));
  std::uint16_t inputs[10];
  const auto t0 = Clock::now();
  for (int k = 0; k < exchanges; ++k) {
    const auto e0 = Clock::now();
    const std::uint16_t cmd[3] = {static_cast<std::uint16_t>(bias_at(k)),
                                  static_cast<std::uint16_t>(k + 1), 1};
    if (modbus_write_registers(ctx, 0, 3, cmd) != 3 ||
        modbus_write_register(ctx, 100, kTicksPerExchange) != 1 ||
        modbus_read_input_registers(ctx, 0, 10, inputs) != 10) {
      throw std::runtime_error(std::string("modbus exchange failed: ") + modbus_strerror(errno));
    }
    latencies_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - e0).count());
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  modbus_close(ctx);
  modbus_free(ctx);
  return figures(latencies_us, wall_s);
}

ExchangeFigures can_lockstep(const std::string& program, const std::vector<std::string>& args,
                             int exchanges) {
  auto all = args;
  all.insert(all.end(), {"--can", "udp://127.0.0.1:0", "--clock", "lockstep"});
  auto s = start(program, all, "can");
  auto uri = drivers::parse_link_uri("can+udp://127.0.0.1:" + std::to_string(s.port));
  auto ep = drivers::can::open_can_endpoint(uri.value(), drivers::can::CanRole::kClient);
  if (!ep) throw std::runtime_error(ep.error().message());
  auto& link = *ep.value();
  std::vector<double> latencies_us;
  latencies_us.reserve(static_cast<std::size_t>(exchanges));
  std::uint16_t expected = 0;
  const auto t0 = Clock::now();
  for (int k = 0; k < exchanges; ++k) {
    const auto e0 = Clock::now();
    const auto counter = static_cast<std::uint8_t>(k & 0x0F);
    (void)link.send(j1939::encode_rig_command(j1939::RigCommand{bias_at(k) * 1e-3, true, counter}));
    (void)link.send(j1939::encode_lockstep(j1939::Lockstep{kTicksPerExchange}));
    expected = static_cast<std::uint16_t>(expected + kTicksPerExchange);
    for (;;) {
      auto f = link.receive(2000ms);
      if (!f) throw std::runtime_error("can exchange failed: " + f.error().message());
      if (j1939::pgn_of(f.value()) != j1939::kPgnPlantSample) continue;
      auto sample = j1939::decode_plant_sample(f.value());
      if (sample && sample->counter == expected) break;
    }
    latencies_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - e0).count());
  }
  return figures(latencies_us, std::chrono::duration<double>(Clock::now() - t0).count());
}

}  // namespace plantsim::bench
