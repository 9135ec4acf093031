// `rig monitor`: condition monitoring of a running set (DESIGN.md section 10), and
// `rig monitor --report monitor.db --out DIR`: the trends of a history.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>

#include "rig/cli/session_commands.hpp"
#include "rig/cli/session_run.hpp"
#include "rig/io/out_dir.hpp"
#include "rig/model/model_file.hpp"
#include "rig/monitor/history.hpp"
#include "rig/monitor/monitor_report.hpp"
#include "rig/session/monitor_session.hpp"

namespace rig::cli {
namespace {

struct MonitorArgs {
  SessionArgs session;
  std::filesystem::path baseline;
  std::filesystem::path history;
  std::filesystem::path report;  // --report: draw a history, run nothing
  session::MonitorOptions options;
  double trip_band_pct = 0.0;  // 0: the test file's band
};

bool inside(const std::filesystem::path& file, const std::filesystem::path& dir) {
  const auto f = std::filesystem::weakly_canonical(std::filesystem::absolute(file));
  const auto d = std::filesystem::weakly_canonical(std::filesystem::absolute(dir));
  const auto rel = f.lexically_relative(d);
  return !rel.empty() && *rel.begin() != "..";
}

int draw_report(const MonitorArgs& a) {
  const monitor::History h = monitor::History::open_read_only(a.report);
  io::prepare_out_dir(a.session.out_dir, a.session.force);
  monitor::write_monitor_report(h, a.session.out_dir);
  fmt::print("rig monitor: report of {} ({} runs): {}\n", a.report.string(), h.runs().size(),
             (a.session.out_dir / "report.html").string());
  return kExitOk;
}

session::MonitorOptions monitor_options(MonitorArgs& a) {
  session::MonitorOptions o = a.options;
  const model::ModelFile m = model::read_model(a.baseline);
  if (!m.tf.is_stable()) {
    throw session::ConfigError(
        fmt::format("--baseline {}: the model is unstable; expected a commissioning model",
                    a.baseline.string()));
  }
  o.baseline = m.tf;
  o.baseline_file = a.baseline.string();
  o.history = a.history.empty() ? a.session.out_dir / "monitor.db" : a.history;
  if (!a.history.empty() && a.session.force && inside(a.history, a.session.out_dir)) {
    throw session::ConfigError(fmt::format(
        "--history {} is inside --out {}, which --force clears: keep the history outside",
        a.history.string(), a.session.out_dir.string()));
  }
  return o;
}

int run_monitor_command(MonitorArgs& a) {
  if (!a.report.empty()) return draw_report(a);
  if (a.baseline.empty()) throw session::ConfigError("--baseline MODEL.json is required");
  session::TestConfig config = load_config(a.session, "monitor");
  if (a.trip_band_pct > 0.0) config.safety.band_pct = a.trip_band_pct;
  if (a.options.band_pct > config.safety.band_pct) {
    throw session::ConfigError(
        fmt::format("--band-pct {:g}: the monitoring band must lie inside the trip band ({:g} %)",
                    a.options.band_pct, config.safety.band_pct));
  }
  session::validate(config);
  const session::MonitorOptions o = monitor_options(a);
  return with_session(a.session, "monitor", [&](const session::SessionOptions& so) {
    const session::MonitorSummary s = session::run_monitor(config, so, o);
    fmt::print(stderr,
               "rig monitor: {} (exit {}); {:.0f} s monitored, {} alarm(s), {} band trip(s), "
               "{} event(s); report: {}\n",
               s.outcome, s.exit_code, s.monitored_s, s.alarms, s.trips, s.events,
               (a.session.out_dir / "report.html").string());
    publish_outcome(so, s.exit_code, s.outcome,
                    {{"monitored_s", s.monitored_s},
                     {"alarms", s.alarms},
                     {"trips", s.trips},
                     {"events", s.events}});
    return s.exit_code;
  });
}

}  // namespace

void add_monitor_command(CLI::App& app) {
  auto a = std::make_shared<MonitorArgs>();
  CLI::App* cmd = app.add_subcommand(
      "monitor",
      "Condition monitoring of a running set: a small permanent excitation, parameter tracking, "
      "parity residuals and named faults; history in SQLite. Ctrl-C ends it normally.");
  add_session_options(*cmd, a->session);
  cmd->add_option("--baseline", a->baseline, "Commissioning model (model.json)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--history", a->history,
                  "SQLite history to continue (default: monitor.db in --out)");
  cmd->add_option("--report", a->report, "Draw the trends of this history into --out and exit")
      ->check(CLI::ExistingFile);
  cmd->add_option("--duration", a->options.duration_s, "Plant seconds to monitor (0: until Ctrl-C)")
      ->default_val(0.0);
  cmd->add_option("--band-pct", a->options.band_pct, "Monitoring band, % of P0")
      ->default_val(1.0)
      ->check(CLI::Range(0.05, 3.0));
  cmd->add_option("--trip-band-pct", a->trip_band_pct, "Supervisor trip band, % of P0 (<= 3)")
      ->check(CLI::Range(0.1, 3.0));
  cmd->add_option("--max-trips", a->options.max_trips, "Band trips within --trip-window that end")
      ->default_val(3);
  cmd->add_option("--trip-window", a->options.trip_window_s, "Window of --max-trips, s")
      ->default_val(3600.0);
  cmd->add_option("--learn", a->options.learn_s, "Baseline spread learnt over this long, s")
      ->default_val(600.0)
      ->check(CLI::Range(60.0, 86400.0));
  cmd->add_option("--false-alarms-per-month", a->options.false_alarms_per_month,
                  "Designed false-alarm rate of all statistics together")
      ->default_val(0.5)
      ->check(CLI::Range(1e-3, 100.0));
  cmd->add_flag("--record", a->options.keep_recording,
                "Also write the full-rate recording.csv (large over days)");
  cmd->callback([a] {
    const int code = run_monitor_command(*a);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace rig::cli
