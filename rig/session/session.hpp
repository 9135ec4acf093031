// The commissioning test (DESIGN.md sections 2 and 8), phase by phase:
//   connect, configure -> steady-state check (nothing written to the governor; refuse to
//   start when it fails) -> activate -> pilot excitation (gain estimate) -> amplitude plan ->
//   excitation with online MMFM until the stopping rule -> ramp-down -> swept sine ->
//   comparison -> deactivate -> outputs (recording, model, FRFs, report).
// Every tick goes through the Supervisor; a trip, a link error or an operator abort ramps the
// bias back to baseline, is recorded with its cause, and sets the exit code:
//   0 pass, 1 acceptance check failed, 2 configuration, 3 link or plant fault (including a
//   refused steady-state check), 4 safety abort (band breach, supervisor trip, operator abort).
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rig/fra/compare.hpp"
#include "rig/fra/frf.hpp"
#include "rig/ident/mmfm.hpp"
#include "rig/io/exit_code.hpp"
#include "rig/live/feed.hpp"
#include "rig/session/online_mmfm.hpp"
#include "rig/session/pilot.hpp"
#include "rig/session/shaped_excitation.hpp"
#include "rig/session/steady_state.hpp"
#include "rig/session/supervisor.hpp"
#include "rig/session/test_config.hpp"
#include "rig/session/tick_loop.hpp"

namespace rig::session {

struct SessionOptions {
  std::filesystem::path out_dir;
  std::string link_uri;  // overrides config.link.uri when set
  std::string preset;    // emulated plant (recorded)
  std::optional<std::uint64_t> plant_seed;
  std::string command = "commission";        // "commission" or "sweep"
  std::FILE* live_out = stderr;              // live view (nullptr: silent)
  const std::atomic<bool>* abort = nullptr;  // set by the SIGINT handler (or the live page)
  live::Feed* feed = nullptr;                // live page and fleet feed (nullptr: off)
};

// The ramp-down at the end of a test or after a trip (DESIGN.md section 8, layer 3).
struct RampDownResult {
  bool attempted = false;  // the external bias had been enabled
  bool cleared = false;    // bias ramped to baseline and enable cleared, acknowledged
  int reconnects = 0;      // reconnections it took
  std::string error;       // why it could not, when !cleared
};

// The activation (DESIGN.md section 8, layer 0).
struct ActivationResult {
  bool acknowledged = false;  // the governor reported the bias active with a live heartbeat
  std::uint16_t status = 0;   // the last status read
  double waited_s = 0.0;
};

// The excitation phase with online MMFM.
struct ExcitationResult {
  std::string type;              // the excitation actually used: shaped, gaussian or prbs
  double planned_std_pct = 0.0;  // from the pilot's amplitude plan
  double applied_std_pct = 0.0;  // measured std of u over the excitation (after supervisor)
  double duration_s = 0.0;
  std::string stop_reason;                         // why the excitation stopped
  std::vector<std::string> quality_flags;          // fatal data-quality findings
  std::vector<BlockEstimate> history;              // one live estimate per block
  std::optional<ident::MmfmResult> mmfm;           // the final estimate
  std::optional<ident::OrderChoice> order_choice;  // its candidate structures (order table)
  std::string mmfm_error;
  signal::Correlation ruu, ryu;     // online correlations (AC-coupled)
  std::vector<model::FrfPoint> h1;  // noise-driven FRF of the excitation record
  // The shaped multisine's design (docs/excitation.md), when one was used.
  std::optional<ShapedDesign> shaped;
};

// Everything the report is made of: the run, one result per phase, the loop's record and the
// outcome.
struct SessionData {
  TestConfig config;
  std::string link_uri;
  std::string command;
  std::string preset;
  std::optional<std::uint64_t> plant_seed;

  std::optional<SteadyStateResult> steady;
  std::optional<ActivationResult> activation;
  std::optional<PilotResult> pilot;
  ExcitationResult excitation;
  std::vector<model::FrfPoint> sweep;  // the swept-sine FRF
  RampDownResult ramp_down;
  std::optional<fra::CompareResult> compare_sweep, compare_h1;

  std::vector<Event> events;
  std::optional<TripRecord> trip;
  TickLoop::Trace trace;
  double max_abs_deviation_pct = 0.0;
  double test_time_s = 0.0;  // plant/test time
  double wall_time_s = 0.0;
  std::optional<LoopTimingSummary> loop_timing;  // when the tick loop ran

  int exit_code = kExitOk;
  std::string outcome;         // one line
  std::string model_rejected;  // why the data do not support a model (then none is written)
};

// Runs the whole test and writes every output file into options.out_dir (which
// rig::io::prepare_out_dir has made fresh). Never throws: every failure is an exit code.
SessionData run_commission(const TestConfig& config, const SessionOptions& options);
// The same over a link the caller made (an in-process fake in the unit tests).
SessionData run_commission(const TestConfig& config, const SessionOptions& options,
                           drivers::GovernorLink& link);

// Exit code for a supervisor trip cause.
int exit_code_for(TripCause cause);

}  // namespace rig::session
