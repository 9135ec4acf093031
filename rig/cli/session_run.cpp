#include "rig/cli/session_run.hpp"

#include <fmt/format.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <memory>

#include "rig/io/out_dir.hpp"
#include "rig/session/emulator.hpp"
#include "rig/session/session.hpp"
#include "rig/session/session_outputs.hpp"

namespace rig::cli {
namespace {

std::atomic<bool> g_abort{false};

void on_sigint(int /*signal*/) { g_abort.store(true); }

// SIGINT and SIGTERM ask for a clean ramp-down instead of killing the rig mid-test.
void install_abort_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  // A file grown past RLIMIT_FSIZE must fail its write (EFBIG, a rig failure the session ramps
  // down from) instead of killing the rig with the bias still applied.
  ::signal(SIGXFSZ, SIG_IGN);
}

// plantsim ticks every 1 ms (its default --tick).
constexpr double kPlantTickS = 1e-3;
constexpr double kLockstepMinTimeoutS = 5.0;

void print_summary(const session::SessionData& d, const std::filesystem::path& out) {
  fmt::print("rig {}: {}\n", d.command, d.outcome);
  if (d.excitation.mmfm && d.excitation.mmfm->derived.valid) {
    const auto& g = d.excitation.mmfm->derived;
    fmt::print(
        "  MMFM: K {:.2f}+-{:.2f} kW/%  fn {:.3f}+-{:.3f} Hz  zeta {:.3f}+-{:.3f}  "
        "Td {:.1f} ms\n",
        g.gain, g.gain_std, g.fn_hz, g.fn_hz_std, g.zeta, g.zeta_std,
        1e3 * d.excitation.mmfm->delay_s);
  }
  if (d.compare_sweep) fmt::print("  vs swept sine: {}\n", d.compare_sweep->summary);
  if (d.compare_h1) fmt::print("  vs H1: {}\n", d.compare_h1->summary);
  fmt::print("  test time {:.1f} s, wall {:.1f} s, largest deviation {:.2f} % of P0\n",
             d.test_time_s, d.wall_time_s, d.max_abs_deviation_pct);
  fmt::print("  report: {}\n", (out / "report.html").string());
}

}  // namespace

session::TestConfig load_config(const SessionArgs& args, const std::string& /*command*/) {
  session::TestConfig c = args.test_file.empty() ? session::parse_test_toml("", "<defaults>")
                                                 : session::load_test_file(args.test_file);
  if (args.emulate) {
    if (args.link_type != "modbus+tcp" && args.link_type != "can+udp" &&
        args.link_type != "modbus+rtu") {
      throw session::ConfigError(fmt::format(
          "--link-type {}: expected modbus+tcp, can+udp or modbus+rtu", args.link_type));
    }
    if (args.clock == "realtime") {
      // The plant integrates in wall time and the rig paces itself on the monotonic clock.
      if (c.link.lockstep_ticks > 0) {
        throw session::ConfigError(fmt::format(
            "--clock realtime: {} sets link.lockstep_ticks = {}; remove it or use --clock "
            "lockstep",
            c.source, c.link.lockstep_ticks));
      }
    } else {
      if (c.link.lockstep_ticks == 0) {
        c.link.lockstep_ticks =
            static_cast<int>(std::lround(1.0 / (c.link.sample_rate_hz * kPlantTickS)));
      }
      // A lockstep plant moves only when told, so a slow answer costs nothing but wall time;
      // the timeout then only has to catch a dead or hung plantsim, not a stalled governor.
      // A short one made busy machines (the RTU link relays through socat) fail spuriously.
      c.link.timeout_s = std::max(c.link.timeout_s, kLockstepMinTimeoutS);
    }
    if (c.plant.preset.empty()) c.plant.preset = args.preset;
    session::validate(c);
  } else if (!args.clock.empty()) {
    throw session::ConfigError(
        "--clock: only with --emulate (a governor link runs in real "
        "time unless link.lockstep_ticks > 0)");
  } else if (args.link.empty() && c.link.uri.empty()) {
    throw session::ConfigError("no link: give --link URI, link.uri in the test file, or --emulate");
  }
  return c;
}

int with_session(const SessionArgs& args, const std::string& command,
                 const std::function<int(const session::SessionOptions&)>& body) {
  install_abort_handler();
  io::prepare_out_dir(args.out_dir, args.force);  // before plantsim or the governor
  LiveOutputs live(args.live, command, g_abort);
  std::unique_ptr<session::EmulatedPlant> plant;
  session::SessionOptions o;
  o.feed = live.feed();
  o.out_dir = args.out_dir;
  o.command = command;
  o.link_uri = args.link;
  o.abort = &g_abort;
  o.live_out = args.quiet ? nullptr : stderr;
  if (args.emulate) {
    session::EmulatorOptions e;
    e.plantsim = session::default_plantsim_path();
    e.preset = args.preset;
    e.seed = args.seed;
    e.link_type = args.link_type;
    e.clock = args.clock.empty() ? "lockstep" : args.clock;
    e.faults = args.faults;
    e.log = args.out_dir / "plantsim.log";
    try {
      plant = std::make_unique<session::EmulatedPlant>(e);
    } catch (const session::EmulatorError& ex) {
      fmt::print(stderr, "rig {}: {}\n", command, ex.what());
      publish_outcome(o, kExitLinkFault, ex.what());
      live.finish(kExitLinkFault);
      return kExitLinkFault;
    }
    o.link_uri = plant->link_uri();
    o.preset = args.preset;
    o.plant_seed = args.seed;
  }
  const int code = body(o);
  if (plant) plant->stop();
  live.finish(code);
  return code;
}

void publish_outcome(const session::SessionOptions& o, int exit_code, const std::string& outcome,
                     const nlohmann::json& extra) {
  if (o.feed == nullptr) return;
  nlohmann::json j = extra;
  j["exit_code"] = exit_code;
  j["outcome"] = outcome;
  o.feed->publish(live::kind::kOutcome, j);
}

int run_session(const SessionArgs& args, session::TestConfig config, const std::string& command) {
  return with_session(args, command, [&](const session::SessionOptions& o) {
    const session::SessionData d = session::run_commission(config, o);
    if (args.json) {
      fmt::print("{}\n", session::report_json(d).dump(2));
    } else {
      print_summary(d, args.out_dir);
    }
    // Scripts and people watching stderr see why it stopped in one line.
    if (d.exit_code != kExitOk) fmt::print(stderr, "rig {}: {}\n", command, d.outcome);
    publish_outcome(o, d.exit_code, d.outcome,
                    {{"model_written", d.excitation.mmfm.has_value() && d.exit_code == kExitOk},
                     {"report", (args.out_dir / "report.html").string()}});
    return d.exit_code;
  });
}

}  // namespace rig::cli
