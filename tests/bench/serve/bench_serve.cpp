// bench_serve: figures for plantsim's serving layer.
//   1. lockstep over Modbus TCP at a 100 Hz exchange (10 ticks of 1 ms per exchange):
//      simulated seconds per wall second, exchange latency p50/p99; against the real plant
//      (build/bin/plantsim) and, as the reference for server overhead measured in the same
//      run, the linear test plant (build/tests/plantsim_linear);
//   2. the same over can+udp;
//   3. the realtime clock at 1 kHz with the real plant in this process, a Modbus server and a
//      rig-like client at 100 Hz: tick jitter p50/p99/max over --jitter-s seconds.
// Usage: bench_serve [--exchanges N] [--jitter-s S] [--plantsim PATH]
#include <fmt/format.h>
#include <modbus/modbus.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <filesystem>
#include <thread>

#include "plantsim/plant/plant.hpp"
#include "plantsim/serve/modbus_node.hpp"
#include "plantsim/serve/realtime_clock.hpp"
#include "tests/bench/serve/lockstep_bench.hpp"

namespace {

using namespace std::chrono_literals;
namespace serve = plantsim::serve;

void print(const char* what, const plantsim::bench::ExchangeFigures& f) {
  fmt::print(
      "{:<44} {:>6} exchanges  {:7.2f} s wall  {:8.1f} sim-s/wall-s  "
      "exchange p50 {:6.0f} us  p99 {:6.0f} us\n",
      what, f.exchanges, f.wall_s, f.sim_per_wall(), f.p50_us, f.p99_us);
}

// A rig at 100 Hz: bias, heartbeat, enable, then the input registers, until `stop`.
void rig_client(int port, const std::atomic<bool>& stop) {
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", port);
  if (ctx == nullptr || modbus_connect(ctx) != 0) return;
  std::uint16_t hb = 0;
  std::uint16_t in[10];
  auto next = std::chrono::steady_clock::now();
  while (!stop) {
    const std::uint16_t cmd[3] = {500, ++hb, 1};
    modbus_write_registers(ctx, 0, 3, cmd);
    modbus_read_input_registers(ctx, 0, 10, in);
    next += 10ms;
    std::this_thread::sleep_until(next);
  }
  modbus_close(ctx);
  modbus_free(ctx);
}

void realtime_jitter(double seconds) {
  plantsim::PlantOptions options;
  serve::Governor governor(plantsim::make_plant(options));
  auto uri = drivers::parse_link_uri("tcp://127.0.0.1:0", "modbus");
  auto node = serve::ModbusNode::open(uri.value(), governor, serve::ClockMode::kRealtime);
  if (!node) throw std::runtime_error(node.error().message());
  const int port =
      std::stoi(node.value()->endpoint().substr(node.value()->endpoint().rfind(':') + 1));
  node.value()->start();
  serve::RealtimeClock clock(governor);
  const auto t0 = std::chrono::steady_clock::now();
  clock.start();
  std::atomic<bool> stop{false};
  std::thread rig([&] { rig_client(port, stop); });
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  stop = true;
  rig.join();
  clock.stop();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  node.value()->stop();
  const auto j = clock.jitter();
  const double plant_s = std::chrono::duration<double>(governor.snapshot().plant_time).count();
  fmt::print(
      "realtime 1 kHz, stornoway, rig at 100 Hz       {:8} ticks over {:.1f} s  jitter "
      "p50 {:.0f} us  p99 {:.0f} us  max {:.0f} us  late>1 tick {}  plant-wall {:+.1f} ms "
      "({})\n",
      j.ticks, wall_s, j.p50_us, j.p99_us, j.max_us, j.late_over_1_tick, (plant_s - wall_s) * 1e3,
      clock.realtime_priority() ? "SCHED_FIFO" : "normal priority: no CAP_SYS_NICE");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_serve: plantsim lockstep throughput and realtime tick jitter"};
  int exchanges = 2000;
  double jitter_s = 60.0;
  const auto here = std::filesystem::absolute(argv[0]).parent_path();
  std::string plantsim = (here / "plantsim").string();
  std::string linear = (here.parent_path() / "tests" / "plantsim_linear").string();
  app.add_option("--exchanges", exchanges, "Lockstep exchanges per measurement")
      ->default_str("2000");
  app.add_option("--jitter-s", jitter_s, "Realtime jitter measurement, seconds (0: skip)")
      ->default_str("60");
  app.add_option("--plantsim", plantsim, "plantsim executable");
  CLI11_PARSE(app, argc, argv);
  try {
    fmt::print("bench_serve: {} lockstep exchanges of 10 ticks x 1 ms (100 Hz rig)\n", exchanges);
    print("lockstep modbus tcp, stornoway (plantsim)",
          plantsim::bench::modbus_lockstep(plantsim, {"--seed", "1"}, exchanges));
    if (std::filesystem::exists(linear)) {
      print("lockstep modbus tcp, linear plant (reference)",
            plantsim::bench::modbus_lockstep(linear, {}, exchanges));
    }
    print("lockstep can+udp, stornoway (plantsim)",
          plantsim::bench::can_lockstep(plantsim, {"--seed", "1"}, exchanges));
    if (std::filesystem::exists(linear)) {
      print("lockstep can+udp, linear plant (reference)",
            plantsim::bench::can_lockstep(linear, {}, exchanges));
    }
    if (jitter_s > 0) realtime_jitter(jitter_s);
  } catch (const std::exception& e) {
    fmt::print(stderr, "bench_serve: {}\n", e.what());
    return 1;
  }
  return 0;
}
