// `rig monitor` (DESIGN.md section 10): a long-running test on a running set under the same
// supervisor and safety layers as a commissioning test.
//
//   steady state -> activate -> { monitor (small permanent excitation, rig::monitor::Monitor)
//       -> on a band trip or a level event: ramp to baseline, wait for a new steady state,
//          re-baseline P0, resume } ... -> Ctrl-C / SIGTERM / --duration: ramp down (normal
//   end, exit 0) -> deactivate -> history and report.
// A trip other than the band (link, heartbeat, bias not applied, rig failure) ends the run
// with its exit code, as in a commissioning test; more than max_trips band trips within
// trip_window_s end it with exit 4.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

#include "rig/model/transfer_function.hpp"
#include "rig/session/session.hpp"
#include "rig/session/test_config.hpp"

namespace rig::session {

struct MonitorOptions {
  model::TransferFunction baseline;  // the commissioning model (plant delay, kW per %)
  std::string baseline_file;
  std::filesystem::path history;  // SQLite file
  double duration_s = 0.0;        // 0: until Ctrl-C / SIGTERM
  double band_pct = 1.0;          // the excitation's own band, % of P0 (<= the trip band)
  int max_trips = 3;              // band trips within trip_window_s that end the run
  double trip_window_s = 3600.0;
  double learn_s = 600.0;               // baseline spread learnt over this much excitation
  double false_alarms_per_month = 0.5;  // designed, all statistics together
  double settle_timeout_s = 600.0;      // longest wait for a new steady state
  bool keep_recording = false;          // full-rate recording.csv (large over days)
  std::FILE* alarms_out = stdout;       // one JSON line per alarm (nullptr: none)
};

struct MonitorSummary {
  int exit_code = 0;
  std::string outcome;
  double monitored_s = 0.0;  // plant time of the run
  long alarms = 0;
  long trips = 0;
  long events = 0;
  double sigma_pct = 0.0;  // planned excitation std, % of rated
};

// Never throws for link or plant faults (exit codes); throws rig::monitor::HistoryError when
// the history cannot be opened (before anything is written to the governor).
MonitorSummary run_monitor(const TestConfig& config, const SessionOptions& options,
                           const MonitorOptions& monitor);

}  // namespace rig::session
