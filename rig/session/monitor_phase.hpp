// The monitoring phase of `rig monitor` (monitor_session.hpp): the small permanent excitation
// under the supervisor, every sample into the monitor's core, its block reports into the
// history, its alarms on stdout (one JSON line each) and in the live view.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "rig/monitor/history.hpp"
#include "rig/monitor/monitor.hpp"
#include "rig/session/monitor_session.hpp"
#include "rig/session/phase.hpp"

namespace rig::session {

// What the monitoring phases of one run share.
struct MonitorRun {
  monitor::Monitor& core;
  monitor::History& history;
  long run_id = 0;
  const MonitorOptions& options;
  MonitorSummary& summary;
  double sigma_pct = 0.0;         // planned excitation std, % of rated
  std::uint64_t seed = 1;         // of the excitation (chunks continue it)
  long chunk = 0;                 // excitation chunks generated so far
  std::string stop_reason;        // set when the run ends normally (operator, duration)
  double history_offset_s = 0.0;  // this run's t = 0 on the history's time axis

  // The core's block report and events into the history, the live view and stdout.
  void publish(RunContext& ctx, const monitor::BlockReport* report);
};

std::unique_ptr<SessionPhase> make_monitor_phase(MonitorRun& run);

// Earlier runs' trends (decimated) and alarms from the history, for a live page opened on
// this run (nothing without a live feed).
void publish_history(const LivePublisher& live, const monitor::History& history, long run_id);

}  // namespace rig::session
