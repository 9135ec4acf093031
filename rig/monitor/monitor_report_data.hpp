// What report.json and report.html of a monitor history are made from (internal to
// rig/monitor/monitor_report*.cpp).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "rig/monitor/history.hpp"

namespace rig::monitor::detail {

struct ReportSeries {
  std::string name;
  SeriesSummary summary;
  std::vector<HistoryPoint> points;  // decimated to kReportPoints
};

struct ReportData {
  std::filesystem::path file;
  std::vector<HistoryRun> runs;
  std::vector<double> run_duration_s;  // per run: up to the next run's offset or the end
  double end_s = 0.0;                  // total monitored (history) time
  std::vector<ReportSeries> series;
  std::vector<HistoryEvent> events;
  std::vector<HistoryAlarm> alarms;
};

void write_monitor_report_html(const ReportData& d, const std::filesystem::path& path);

}  // namespace rig::monitor::detail
