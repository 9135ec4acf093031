// report.html of a monitor history: summary, runs, alarms, one trend per series over history
// time with its thresholds and markers at alarms and trips, and the latest events.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rig/monitor/monitor_report.hpp"
#include "rig/monitor/monitor_report_data.hpp"
#include "rig/report/html_report.hpp"

namespace rig::monitor::detail {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kThresholdColor = "#d62728";
constexpr const char* kAlarmColor = "#ff7f0e";
constexpr const char* kTripColor = "#000000";

std::string hours(double s) { return fmt::format("{:.3f}", s / 3600.0); }

std::string duration_text(double s) {
  if (s >= 48 * 3600.0) return fmt::format("{:.1f} h ({:.1f} days)", s / 3600.0, s / 86400.0);
  if (s >= 3600.0) return fmt::format("{:.2f} h", s / 3600.0);
  return fmt::format("{:.0f} s", s);
}

std::string or_dash(const std::string& text) { return text.empty() ? "-" : text; }

void summary(report::HtmlReport& page, const ReportData& d) {
  if (d.alarms.empty()) {
    page.note(report::Tone::kOk,
              fmt::format("no alarm in {} of monitoring", duration_text(d.end_s)));
  } else {
    const HistoryAlarm& last = d.alarms.back();
    page.note(report::Tone::kWarning,
              fmt::format("{} alarm(s); the latest at {} h ({}): {}", d.alarms.size(),
                          hours(last.history_s), last.utc, last.alarm.cause));
  }
  std::vector<std::pair<std::string, std::string>> kv = {
      {"history file", d.file.string()},
      {"runs", std::to_string(d.runs.size())},
      {"total monitored time", duration_text(d.end_s)},
      {"alarms", std::to_string(d.alarms.size())},
      {"events", std::to_string(d.events.size())},
      {"series", std::to_string(d.series.size())}};
  if (!d.runs.empty()) {
    kv.push_back({"first run started", or_dash(d.runs.front().started_utc)});
    const HistoryRun& last = d.runs.back();
    kv.push_back({"last run", last.ended_utc.empty()
                                  ? "running, or ended without closing the history"
                                  : fmt::format("ended {}: {}", last.ended_utc, last.outcome)});
  }
  page.section("Summary").key_values(kv);
}

void runs_table(report::HtmlReport& page, const ReportData& d) {
  if (d.runs.empty()) return;
  report::Table t{{"run", "started (UTC)", "ended (UTC)", "from (h)", "duration", "link", "preset",
                   "seed", "P0 (kW)", "exit", "outcome"},
                  {},
                  {}};
  for (std::size_t i = 0; i < d.runs.size(); ++i) {
    const HistoryRun& r = d.runs[i];
    t.rows.push_back({std::to_string(r.id), or_dash(r.started_utc), or_dash(r.ended_utc),
                      hours(r.offset_s), duration_text(d.run_duration_s[i]), or_dash(r.info.link),
                      or_dash(r.info.preset), std::to_string(r.info.seed),
                      fmt::format("{:.1f}", r.info.p0_kw),
                      r.exit_code ? std::to_string(*r.exit_code) : "-", or_dash(r.outcome)});
  }
  page.section("Runs").table(t);
}

void alarms_table(report::HtmlReport& page, const ReportData& d) {
  page.section("Alarms");
  if (d.alarms.empty()) {
    page.paragraph("No alarm was raised.");
    return;
  }
  report::Table t{
      {"when (h)", "UTC", "run", "cause", "class", "confidence", "onset (run s)", "what to check"},
      {},
      {}};
  for (const HistoryAlarm& h : d.alarms) {
    const AlarmRecord& a = h.alarm;
    t.rows.push_back({hours(h.history_s), h.utc, std::to_string(h.run_id), a.cause, a.fault_class,
                      fmt::format("{:.0f} %", 100.0 * a.confidence),
                      fmt::format("{:.1f}", a.onset_s), a.check});
  }
  page.table(t);
}

// The index of x nearest to v (x sorted, not empty).
std::size_t nearest(const std::vector<double>& x, double v) {
  const auto it = std::lower_bound(x.begin(), x.end(), v);
  if (it == x.begin()) return 0;
  if (it == x.end()) return x.size() - 1;
  const auto i = static_cast<std::size_t>(it - x.begin());
  return v - x[i - 1] <= x[i] - v ? i - 1 : i;
}

// Points on the trend at the given history times (snapped to the nearest drawn sample; times
// farther than one mean spacing outside the trend are left out).
report::Series markers(const report::Chart& c, const std::vector<double>& times_s,
                       const std::string& label, const std::string& color) {
  report::Series m{label, std::vector<double>(c.x.size(), kNaN), color, false, true, 3.0};
  const double margin = (c.x.back() - c.x.front()) / static_cast<double>(c.x.size());
  for (double t : times_s) {
    const double h = t / 3600.0;
    if (h < c.x.front() - margin || h > c.x.back() + margin) continue;
    const std::size_t i = nearest(c.x, h);
    for (const report::Series& s : c.series) {
      if (std::isfinite(s.y[i])) {
        m.y[i] = s.y[i];
        break;
      }
    }
  }
  return m;
}

report::Chart trend_chart(const ReportSeries& s, const std::vector<double>& alarm_s,
                          const std::vector<double>& trip_s) {
  report::Chart c{s.name, "history time (h)", s.name, {}, {}, {}, false, false, 240};
  report::Series value{s.name, {}, "#1f77b4", false, false, 1.5};
  report::Series lo{"lo threshold", {}, kThresholdColor, true, false, 1.0};
  report::Series hi{"hi threshold", {}, kThresholdColor, true, false, 1.0};
  for (const HistoryPoint& p : s.points) {
    c.x.push_back(p.history_s / 3600.0);
    value.y.push_back(p.value);
    lo.y.push_back(p.lo.value_or(kNaN));
    hi.y.push_back(p.hi.value_or(kNaN));
  }
  const auto any = [](const report::Series& t) {
    return std::any_of(t.y.begin(), t.y.end(), [](double v) { return std::isfinite(v); });
  };
  c.series.push_back(value);
  if (any(lo)) c.series.push_back(lo);
  if (any(hi)) c.series.push_back(hi);
  const report::Series alarms = markers(c, alarm_s, "alarm", kAlarmColor);
  const report::Series trips = markers(c, trip_s, "trip", kTripColor);
  if (!alarm_s.empty()) c.series.push_back(alarms);
  if (!trip_s.empty()) c.series.push_back(trips);
  return c;
}

void trends(report::HtmlReport& page, const ReportData& d) {
  page.section("Trends");
  if (d.series.empty()) {
    page.paragraph("No value was recorded.");
    return;
  }
  page.paragraph(fmt::format(
      "History time runs on from one run to the next. Dashed: the alarm thresholds; markers: "
      "alarms (orange) and trips (black). Long series are evenly thinned to at most {} points.",
      kReportPoints));
  std::vector<double> alarm_s, trip_s;
  for (const auto& a : d.alarms) alarm_s.push_back(a.history_s);
  for (const auto& e : d.events)
    if (e.kind == "trip") trip_s.push_back(e.history_s);
  for (const ReportSeries& s : d.series) {
    if (!s.points.empty()) page.chart(trend_chart(s, alarm_s, trip_s));
  }
}

void events_table(report::HtmlReport& page, const ReportData& d) {
  page.section("Events");
  if (d.events.empty()) {
    page.paragraph("No event was recorded.");
    return;
  }
  const std::size_t from = d.events.size() > kMaxEventRows ? d.events.size() - kMaxEventRows : 0;
  if (from > 0) {
    page.note(report::Tone::kInfo,
              fmt::format("The last {} of {} events; report.json lists them all.", kMaxEventRows,
                          d.events.size()));
  }
  report::Table t{{"when (h)", "UTC", "run", "kind", "event"}, {}, {}};
  for (std::size_t i = from; i < d.events.size(); ++i) {
    const HistoryEvent& e = d.events[i];
    t.rows.push_back({hours(e.history_s), e.utc, std::to_string(e.run_id), e.kind, e.text});
  }
  page.table(t);
}

}  // namespace

void write_monitor_report_html(const ReportData& d, const std::filesystem::path& path) {
  report::HtmlReport page("rig monitor: " + d.file.filename().string());
  summary(page, d);
  runs_table(page, d);
  alarms_table(page, d);
  trends(page, d);
  events_table(page, d);
  page.write(path);
}

}  // namespace rig::monitor::detail
