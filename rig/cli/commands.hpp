// Subcommands of the `rig` executable (DESIGN.md section 4). main.cpp registers each with
// one line. Convention: a subcommand's callback throws CLI::RuntimeError(code) for a
// non-zero exit code; main() returns it (parse errors become kExitUsage).
#pragma once

#include "rig/io/exit_code.hpp"

namespace CLI {
class App;
}

namespace rig::cli {

// Exit codes: rig::ExitCode (rig/io/exit_code.hpp), the one definition for every command.

// rig identify --recording REC.csv [...] --out DIR   (identify.cpp)
void add_identify_command(CLI::App& app);

// Parses and runs; returns the process exit code (help: 0; parse errors: kExitUsage).
int run_app(CLI::App& app, int argc, char** argv);

}  // namespace rig::cli
