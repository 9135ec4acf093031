// `rig commission`: the commissioning test (DESIGN.md section 4).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>

#include "rig/cli/session_commands.hpp"
#include "rig/cli/session_run.hpp"
#include "rig/session/session.hpp"

namespace rig::cli {

void add_session_options(CLI::App& cmd, SessionArgs& a) {
  cmd.add_option("--link", a.link, "Governor link URI, e.g. modbus+tcp://10.0.0.5:502?unit=1");
  cmd.add_option("--test", a.test_file, "Test file (TOML, see docs/test-file.md)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--out", a.out_dir, "Output folder (must be new or empty, see --force)")
      ->required();
  cmd.add_flag("--emulate", a.emulate, "Start plantsim (see --clock) and test against it");
  cmd.add_option("--preset", a.preset,
                 "Emulated plant: a preset name, or a plant TOML (plantsim --list-params "
                 "writes one to edit)")->default_str("stornoway");
  cmd.add_option("--seed", a.seed, "Emulated plant noise seed")->default_str("1");
  cmd.add_option("--link-type", a.link_type, "Emulated link: modbus+tcp, can+udp, modbus+rtu")
      ->default_str("modbus+tcp");
  cmd.add_option("--clock", a.clock,
                 "Emulated plant clock: lockstep (fast, reproducible) or realtime (paced on the "
                 "monotonic clock, loop timing measured)")
      ->check(CLI::IsMember({"lockstep", "realtime"}))
      ->default_str("lockstep");
  cmd.add_option("--fault", a.faults, "Emulated plant fault NAME=VALUE@t=SECONDS (repeatable)");
  cmd.add_flag("--json", a.json, "Print report.json on stdout instead of the summary");
  cmd.add_flag("--quiet", a.quiet, "No live view");
  cmd.add_flag("--force", a.force, "Clear a non-empty --out folder first (an earlier run's files)");
  add_live_options(cmd, a.live);
}

void add_live_options(CLI::App& cmd, LiveArgs& a) {
  cmd.add_option("--http", a.http,
                 "Serve a live page on HOST:PORT (or PORT on 127.0.0.1; 0: any free port); its "
                 "Stop button needs the token printed on the console");
  cmd.add_option("--mqtt", a.mqtt,
                 "Publish state, estimates, alarms and the outcome to an MQTT broker: "
                 "mqtt://HOST[:PORT]/TOPIC_PREFIX (topics PREFIX/SET_ID/..., docs/live.md)");
  cmd.add_option("--set-id", a.set_id, "The set's id in MQTT topics and page titles")
      ->default_str("the host name");
}

void add_commission_command(CLI::App& app) {
  auto args = std::make_shared<SessionArgs>();
  CLI::App* cmd =
      app.add_subcommand("commission",
                         "Commissioning test: steady-state check, pilot, excitation with online "
                         "MMFM, swept sine, comparison, report");
  add_session_options(*cmd, *args);
  cmd->callback([args] {
    const int code = run_session(*args, load_config(*args, "commission"), "commission");
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace rig::cli
