// Subcommands of the `rig` executable (DESIGN.md section 4). main.cpp registers each with
// one line. Convention: a subcommand's callback throws CLI::RuntimeError(code) for a
// non-zero exit code; main() returns it (parse errors become kExitUsage).
#pragma once

namespace CLI {
class App;
}

namespace rig::cli {

enum ExitCode : int {
  kExitOk = 0,
  kExitAcceptance = 1,  // the command ran, its acceptance / data-quality checks failed
  kExitUsage = 2,       // usage, configuration or input-file error
  kExitLinkFault = 3,   // link or plant fault, test aborted safely
  kExitSafety = 4,      // power-limit breach or supervisor trip
};

// rig identify --recording REC.csv [...] --out DIR   (identify.cpp)
void add_identify_command(CLI::App& app);

// Parses and runs; returns the process exit code (help: 0; parse errors: kExitUsage).
int run_app(CLI::App& app, int argc, char** argv);

}  // namespace rig::cli
