// `rig sweep`: a swept-sine frequency response on its own (DESIGN.md section 4). The same
// steady-state check, pilot and supervisor as `rig commission` guard it.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>

#include "rig/cli/session_commands.hpp"
#include "rig/cli/session_run.hpp"
#include "rig/session/session.hpp"

namespace rig::cli {

namespace {
struct SweepArgs {
  SessionArgs session;
  std::optional<double> from_hz, to_hz;
  std::optional<int> points;
};
}  // namespace

void add_sweep_command(CLI::App& app) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand("sweep", "Swept-sine frequency response (sweep.csv)");
  add_session_options(*cmd, args->session);
  cmd->add_option("--from", args->from_hz, "Lowest frequency, Hz");
  cmd->add_option("--to", args->to_hz, "Highest frequency, Hz");
  cmd->add_option("--points", args->points, "Log-spaced frequencies");
  cmd->callback([args] {
    session::TestConfig c = load_config(args->session, "sweep");
    if (args->from_hz) c.sweep.from_hz = *args->from_hz;
    if (args->to_hz) c.sweep.to_hz = *args->to_hz;
    if (args->points) c.sweep.points = *args->points;
    c.sweep.enabled = true;
    session::validate(c);
    const int code = run_session(args->session, c, "sweep");
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace rig::cli
