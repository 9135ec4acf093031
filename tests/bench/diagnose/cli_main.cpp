// diagnose_cli: `rig diagnose` on its own (same command object as the rig executable), for
// benchmarks and examples: diagnose_cli diagnose --recording ... --model ... --out ...
#include <CLI/CLI.hpp>

#include "rig/cli/commands.hpp"
#include "rig/cli/diagnose.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rig diagnose"};
  app.require_subcommand(1);
  rig::cli::add_diagnose_command(app);
  return rig::cli::run_app(app, argc, argv);
}
