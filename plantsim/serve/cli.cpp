// Command-line parsing for `plantsim` (CLI11). Everything here only fills ServeOptions;
// serve() in app.cpp does the work.
#include <fmt/format.h>
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "plantsim/serve/app.hpp"
#include "plantsim/serve/endpoint.hpp"

namespace plantsim::serve {
namespace {

// Options CLI11 stores as text; validate() turns them into ServeOptions.
struct TextOptions {
  std::string clock = "realtime";
  std::string tick = "1ms";
  std::string rig_address = "0xF9";
  std::string sample_period = "command";
  bool exit_with_parent = false;
};

void add_options(CLI::App& app, ServeOptions& o, TextOptions& t) {
  app.add_option("--preset", o.plant.preset, "Plant preset")->default_str("stornoway");
  app.add_option("--config", o.plant.config, "Plant TOML (overrides --preset)");
  app.add_option("--modbus", o.modbus,
                 "Modbus endpoint: tcp://HOST:PORT (port 0 = ephemeral) or "
                 "rtu:DEVICE?baud=19200[&parity=N][&unit=1] (default tcp://127.0.0.1:1502)");
  app.add_option("--can", o.can, "CAN endpoint: udp://HOST:PORT or socketcan:IFACE");
  app.add_option("--clock", t.clock,
                 "realtime (plant follows the monotonic clock) or lockstep "
                 "(plant advances only when the rig writes holding 100 / "
                 "sends PGN 0xFF52)")
      ->default_str("realtime");
  app.add_option("--tick", t.tick, "Plant tick, e.g. 1ms, 500us")->default_str("1ms");
  app.add_option("--can-rig-address", t.rig_address,
                 "CAN: the only source address whose commands (0xFF50, TSC1, 0xFF52) the "
                 "governor accepts, 0-253 (0x.. for hex)")
      ->default_str("0xF9");
  app.add_option("--can-sample-period", t.sample_period,
                 "CAN, realtime: send PGN 0xFF51 every PERIOD of plant time (e.g. 10ms), or "
                 "'command' to answer each accepted command (lockstep: one per 0xFF52)")
      ->default_str("command");
  app.add_option("--fault", o.plant.faults,
                 "Parameter change NAME=VALUE@t=SECONDS[,ramp=SECONDS] (plant time, repeatable; "
                 "a ramp moves linearly from the value at t to VALUE); interface "
                 "faults serve.freeze_counter, serve.nan_power, serve.drop_link =1 (on) or 0 "
                 "(off), e.g. serve.nan_power=1@t=30");
  app.add_option("--seed", o.plant.seed, "Seed of the plant's noise")->default_str("1");
  app.add_option("--duration", o.duration_s, "Stop after this much plant time (seconds)");
  app.add_option("--linearise", o.linearise_to,
                 "Write the linearised bias-to-power transfer function JSON and exit");
  app.add_option("--replay", o.replay_in,
                 "Replay a recorded bias (CSV with header, time column t, bias in %) through "
                 "the plant without noise, drift, pick-up, ripple or quantisation, tick = the "
                 "recording's period; needs --replay-out; exits when done");
  app.add_option("--replay-out", o.replay_out, "Replay output CSV: t,u,power_kw");
  app.add_option("--replay-column", o.replay_column, "Bias column of the replay input")
      ->default_str("u");
  app.add_flag("--readout", o.readout, "Print power, speed and bias once a second");
  app.add_flag("--exit-with-parent", t.exit_with_parent,
               "Stop (as on SIGTERM) when the process that started plantsim dies, so that a "
               "crashed rig never leaves an emulated plant running");
  app.add_flag("--list-params", o.list_params,
               "Print every plant parameter (of --preset/--config) as TOML with units and "
               "ranges, and exit");
}

std::uint8_t parse_rig_address(const std::string& text) {
  std::size_t used = 0;
  unsigned long v = 0;
  try {
    v = std::stoul(text, &used, 0);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || v > 253) {
    throw ConfigError(fmt::format(
        "--can-rig-address '{}': expected a J1939 source address 0-253 (e.g. 0xF9)", text));
  }
  return static_cast<std::uint8_t>(v);
}

std::chrono::nanoseconds parse_sample_period(const std::string& text) {
  if (text == "command") return std::chrono::nanoseconds(0);
  try {
    return parse_tick(text);
  } catch (const ConfigError&) {
    throw ConfigError(fmt::format(
        "--can-sample-period '{}': expected 'command' or a period such as 10ms (100us .. 1s)",
        text));
  }
}

// Checks that CLI11 cannot express, each with a one-line message.
void validate(ServeOptions& o, const TextOptions& t) {
  const std::string& clock = t.clock;
  if (clock == "realtime") {
    o.clock = ClockMode::kRealtime;
  } else if (clock == "lockstep") {
    o.clock = ClockMode::kLockstep;
  } else {
    throw ConfigError(fmt::format("--clock '{}': expected realtime or lockstep", clock));
  }
  o.can_node.rig_address = parse_rig_address(t.rig_address);
  o.can_node.sample_period = parse_sample_period(t.sample_period);
  o.plant.tick = parse_tick(t.tick);
  o.serve_faults = split_serve_faults(o.plant.faults);
  if (o.duration_s && !(*o.duration_s > 0.0 && *o.duration_s < 1e7)) {
    throw ConfigError(fmt::format("--duration {}: expected seconds > 0", *o.duration_s));
  }
  if (o.replay_in.has_value() != o.replay_out.has_value()) {
    throw ConfigError("--replay and --replay-out: expected both or neither");
  }
  if (o.modbus) parse_modbus_endpoint(*o.modbus);
  if (o.can) parse_can_endpoint(*o.can);
  if (!o.modbus && !o.can) o.modbus = "tcp://127.0.0.1:1502";
}

}  // namespace

int plantsim_main(int argc, char** argv, const PlantHooks& hooks) {
  CLI::App app{
      "plantsim: emulated governor / diesel engine / alternator plant serving the "
      "rig's Modbus and CAN maps"};
  ServeOptions options;
  TextOptions text;
  add_options(app, options, text);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "plantsim: " << e.what() << " (see --help)\n";
    return 2;
  }
  try {
    validate(options, text);
  } catch (const ConfigError& e) {
    std::cerr << "plantsim: " << e.what() << "\n";
    return 2;
  }
  if (text.exit_with_parent) {
    // The parent that started us (rig --emulate) dies: SIGTERM, the normal stop.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() == 1) return 0;  // it died before prctl took effect
  }
  return serve(options, hooks);
}

}  // namespace plantsim::serve
