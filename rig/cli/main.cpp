// The `rig` executable: one line per subcommand (DESIGN.md section 4).
#include <CLI/CLI.hpp>

#include "rig/cli/commands.hpp"
#include "rig/cli/diagnose.hpp"
#include "rig/cli/session_commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rig: hardware-in-the-loop test rig for diesel generator sets"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "rig 0.1.0");
  rig::cli::add_commission_command(app);
  rig::cli::add_sweep_command(app);
  rig::cli::add_compare_command(app);
  rig::cli::add_monitor_command(app);
  rig::cli::add_identify_command(app);
  rig::cli::add_diagnose_command(app);
  return rig::cli::run_app(app, argc, argv);
}
