// The report of a monitor history (`rig monitor --report`): report.json and report.html in
// out_dir (created when missing), both written atomically.
//
// report.json keys: "command" ("monitor report"), "history" (the file), "total_monitored_s"
// (history time at the end of the last run), "counts" {runs, series, events, alarms}, "runs"
// (id, started_utc, ended_utc, offset_s, duration_s, link, baseline, preset, seed, p0_kw,
// exit_code, outcome), "series" (per name: count, first/last history_s, min, max and the
// decimated "points" {history_s, run_id, value, lo, hi}), "events" (every event) and
// "alarms" (every alarm, evidence as JSON). Non-finite numbers and missing thresholds: null.
//
// report.html: a summary, the runs, the alarms, one trend chart per series over history time
// (hours) with its thresholds dashed and markers at alarms and trips, and the last
// kMaxEventRows events.
#pragma once

#include <cstddef>
#include <filesystem>

#include "rig/monitor/history.hpp"

namespace rig::monitor {

inline constexpr std::size_t kReportPoints = 4000;  // per series, in both files
inline constexpr std::size_t kMaxEventRows = 200;   // events listed in report.html

// Throws HistoryError when the history cannot be read and rig::io::InputError when out_dir is
// not writable.
void write_monitor_report(const History& h, const std::filesystem::path& out_dir);

}  // namespace rig::monitor
