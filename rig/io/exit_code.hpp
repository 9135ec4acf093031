// The process exit codes of every `rig` command (DESIGN.md section 4), in one place. Scripts
// rely on them, so they never change meaning.
#pragma once

namespace rig {

enum ExitCode : int {
  kExitOk = 0,          // success
  kExitAcceptance = 1,  // ran, but its acceptance / data-quality checks failed (no model)
  kExitUsage = 2,       // usage, configuration, input file or output folder error
  kExitLinkFault = 3,   // link or plant fault (test aborted safely)
  kExitSafety = 4,      // band breach, supervisor trip, rig failure (disk full), operator abort
};

}  // namespace rig
