#include "plantsim/serve/app.hpp"

#include <fmt/format.h>
#include <signal.h>

#include <csignal>
#include <cstdio>
#include <iostream>

#include "plantsim/plant/replay.hpp"
#include "plantsim/serve/can_node.hpp"
#include "plantsim/serve/realtime_clock.hpp"

namespace plantsim::serve {
namespace {

using Clock = std::chrono::steady_clock;

// Everything serve() started, stopped in reverse order by the destructor on every path.
struct Running {
  std::unique_ptr<Governor> governor;
  std::unique_ptr<ModbusNode> modbus;
  std::unique_ptr<CanNode> can;
  std::unique_ptr<RealtimeClock> clock;
  ~Running() {
    if (clock) clock->stop();
    if (can) can->stop();
    if (modbus) modbus->stop();
  }
};

// Blocks SIGINT/SIGTERM in this thread (and so in every thread started after it); the main
// loop takes them synchronously with sigtimedwait.
sigset_t block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

void print_readout(const Governor& governor) {
  const auto s = governor.snapshot();
  std::printf("plantsim: t=%.3f s  P=%.1f kW  n=%.1f rpm  f=%.3f Hz  bias=%.3f %%%s\n",
              std::chrono::duration<double>(s.plant_time).count(), s.measurement.power_w / 1e3,
              s.measurement.speed_rpm, s.measurement.freq_hz, s.bias_applied_pct,
              s.heartbeat_lost ? "  (heartbeat lost)" : "");
  std::fflush(stdout);
}

void print_summary(const Running& r) {
  const auto s = r.governor->snapshot();
  std::string line = fmt::format("plantsim: stopped at t={:.3f} s after {} ticks",
                                 std::chrono::duration<double>(s.plant_time).count(), s.ticks);
  if (r.clock) {
    const auto j = r.clock->jitter();
    line += fmt::format("; tick jitter p50 {:.0f} us p99 {:.0f} us max {:.0f} us ({})", j.p50_us,
                        j.p99_us, j.max_us,
                        r.clock->realtime_priority() ? "SCHED_FIFO" : "normal priority");
  }
  if (r.modbus) {
    const auto c = r.modbus->counters();
    line += fmt::format("; modbus {} requests, {} malformed", c.requests, c.malformed);
  }
  if (r.can) {
    const auto c = r.can->counters();
    line += fmt::format("; can {} frames in, {} rejected ({} from another source address)",
                        c.received, c.rejected(), c.wrong_source);
  }
  std::cerr << line << "\n";
}

// Opens every endpoint; returns false (after printing one line) if any cannot be opened.
bool open_endpoints(const ServeOptions& o, Running& r) {
  if (o.modbus) {
    auto node = ModbusNode::open(parse_modbus_endpoint(*o.modbus), *r.governor, o.clock);
    if (!node) {
      std::cerr << "plantsim: --modbus " << node.error().where << ": " << node.error().detail
                << "\n";
      return false;
    }
    r.modbus = std::move(node.value());
  }
  if (o.can) {
    auto node = CanNode::open(parse_can_endpoint(*o.can), *r.governor, o.clock, o.can_node);
    if (!node) {
      std::cerr << "plantsim: --can " << node.error().where << ": " << node.error().detail << "\n";
      return false;
    }
    r.can = std::move(node.value());
  }
  return true;
}

// Serves until a stop signal, --duration of plant time, or a transport failure.
int wait_for_stop(const ServeOptions& o, Running& r, const sigset_t& stop_signals) {
  const auto duration = o.duration_s
                            ? std::optional(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                  std::chrono::duration<double>(*o.duration_s)))
                            : std::nullopt;
  auto next_readout = Clock::now() + std::chrono::seconds(1);
  const timespec poll{0, 20'000'000};
  for (;;) {
    if (sigtimedwait(&stop_signals, nullptr, &poll) > 0) return 0;
    if (duration && r.governor->snapshot().plant_time >= *duration) return 0;
    if (r.modbus && r.modbus->failure()) {
      std::cerr << "plantsim: modbus " << r.modbus->failure()->message() << "\n";
      return 3;
    }
    if (r.can && r.can->failure()) {
      std::cerr << "plantsim: can " << r.can->failure()->message() << "\n";
      return 3;
    }
    if (o.readout && Clock::now() >= next_readout) {
      print_readout(*r.governor);
      next_readout += std::chrono::seconds(1);
    }
  }
}

}  // namespace

int serve(const ServeOptions& o, const PlantHooks& hooks) {
  const sigset_t stop_signals = block_stop_signals();
  std::signal(SIGPIPE, SIG_IGN);  // a reader of --readout going away must not kill the plant
  Running r;
  try {
    if (o.list_params) {
      if (!hooks.list_params) {
        std::cerr << "plantsim: --list-params is not available in this build\n";
        return 2;
      }
      std::cout << hooks.list_params(o.plant) << std::flush;
      return 0;
    }
    if (o.linearise_to) {
      if (!hooks.linearise) {
        std::cerr << "plantsim: --linearise is not available in this build\n";
        return 2;
      }
      hooks.linearise(o.plant, *o.linearise_to);
      return 0;
    }
    if (o.replay_in) {
      const ReplayInput input = read_replay_csv(*o.replay_in, o.replay_column);
      std::vector<double> power_kw;
      try {
        power_kw = replay(input, o.plant, hooks.make_plant);
      } catch (const ConfigError&) {
        throw;
      } catch (const std::runtime_error& e) {  // the solver failed: a plant fault
        std::cerr << "plantsim: " << e.what() << "\n";
        return 3;
      }
      write_replay_csv(*o.replay_out, input, power_kw);
      return 0;
    }
    r.governor = std::make_unique<Governor>(hooks.make_plant(o.plant));
    r.governor->set_serve_faults(ServeFaultSchedule(o.serve_faults));
    if (!open_endpoints(o, r)) return 2;
  } catch (const ConfigError& e) {
    std::cerr << "plantsim: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {  // e.g. --linearise to an unwritable path
    std::cerr << "plantsim: " << e.what() << "\n";
    return 2;
  }
  if (r.modbus) std::printf("plantsim: modbus %s ready\n", r.modbus->endpoint().c_str());
  if (r.can) std::printf("plantsim: can %s ready\n", r.can->endpoint().c_str());
  std::fflush(stdout);
  if (r.modbus) r.modbus->start();
  if (r.can) r.can->start();
  if (o.clock == ClockMode::kRealtime) {
    r.clock = std::make_unique<RealtimeClock>(*r.governor);
    r.clock->start();
  }
  const int code = wait_for_stop(o, r, stop_signals);
  if (r.clock) r.clock->stop();
  print_summary(r);
  return code;
}

}  // namespace plantsim::serve
