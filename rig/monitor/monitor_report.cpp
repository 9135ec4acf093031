#include "rig/monitor/monitor_report.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <system_error>

#include "rig/io/input_error.hpp"
#include "rig/monitor/monitor_report_data.hpp"
#include "rig/report/json_out.hpp"

namespace rig::monitor {
namespace {

using nlohmann::json;
using report::number_or_null;

json optional_number(const std::optional<double>& v) {
  return v ? number_or_null(*v) : json(nullptr);
}

json text_or_null(const std::string& text) { return text.empty() ? json(nullptr) : json(text); }

detail::ReportData gather(const History& h) {
  detail::ReportData d;
  d.file = h.file();
  d.runs = h.runs();
  d.events = h.events();
  d.alarms = h.alarms();
  for (const std::string& name : h.series_names()) {
    d.series.push_back({name, h.series_summary(name), h.series(name, kReportPoints)});
    d.end_s = std::max(d.end_s, d.series.back().summary.last_history_s);
  }
  for (const auto& e : d.events) d.end_s = std::max(d.end_s, e.history_s);
  for (const auto& a : d.alarms) d.end_s = std::max(d.end_s, a.history_s);
  for (const auto& r : d.runs) d.end_s = std::max(d.end_s, r.offset_s);
  for (std::size_t i = 0; i < d.runs.size(); ++i) {
    const double next = i + 1 < d.runs.size() ? d.runs[i + 1].offset_s : d.end_s;
    d.run_duration_s.push_back(std::max(0.0, next - d.runs[i].offset_s));
  }
  return d;
}

json runs_json(const detail::ReportData& d) {
  json out = json::array();
  for (std::size_t i = 0; i < d.runs.size(); ++i) {
    const HistoryRun& r = d.runs[i];
    out.push_back({{"id", r.id},
                   {"started_utc", text_or_null(r.started_utc)},
                   {"ended_utc", text_or_null(r.ended_utc)},
                   {"offset_s", number_or_null(r.offset_s)},
                   {"duration_s", number_or_null(d.run_duration_s[i])},
                   {"link", r.info.link},
                   {"baseline", r.info.baseline},
                   {"preset", r.info.preset},
                   {"seed", r.info.seed},
                   {"p0_kw", number_or_null(r.info.p0_kw)},
                   {"exit_code", r.exit_code ? json(*r.exit_code) : json(nullptr)},
                   {"outcome", text_or_null(r.outcome)}});
  }
  return out;
}

json series_json(const detail::ReportSeries& s) {
  json history_s = json::array(), run_id = json::array(), value = json::array();
  json lo = json::array(), hi = json::array();
  for (const HistoryPoint& p : s.points) {
    history_s.push_back(number_or_null(p.history_s));
    run_id.push_back(p.run_id);
    value.push_back(number_or_null(p.value));
    lo.push_back(optional_number(p.lo));
    hi.push_back(optional_number(p.hi));
  }
  return {{"name", s.name},
          {"count", s.summary.count},
          {"first_history_s", number_or_null(s.summary.first_history_s)},
          {"last_history_s", number_or_null(s.summary.last_history_s)},
          {"min", optional_number(s.summary.min)},
          {"max", optional_number(s.summary.max)},
          {"points",
           {{"shown", s.points.size()},
            {"history_s", history_s},
            {"run_id", run_id},
            {"value", value},
            {"lo", lo},
            {"hi", hi}}}};
}

json events_json(const std::vector<HistoryEvent>& events) {
  json out = json::array();
  for (const HistoryEvent& e : events) {
    out.push_back({{"run_id", e.run_id},
                   {"t_s", number_or_null(e.t_s)},
                   {"history_s", number_or_null(e.history_s)},
                   {"utc", e.utc},
                   {"kind", e.kind},
                   {"text", e.text}});
  }
  return out;
}

json alarms_json(const std::vector<HistoryAlarm>& alarms) {
  json out = json::array();
  for (const HistoryAlarm& h : alarms) {
    const AlarmRecord& a = h.alarm;
    // Evidence that is not valid JSON (written by hand or by an older monitor) as text.
    json evidence = json::parse(a.evidence_json, nullptr, false);
    if (evidence.is_discarded()) evidence = a.evidence_json;
    out.push_back({{"run_id", h.run_id},
                   {"t_s", number_or_null(a.t_s)},
                   {"history_s", number_or_null(h.history_s)},
                   {"utc", h.utc},
                   {"cause", a.cause},
                   {"fault_class", a.fault_class},
                   {"confidence", number_or_null(a.confidence)},
                   {"onset_s", number_or_null(a.onset_s)},
                   {"check", a.check},
                   {"evidence", evidence}});
  }
  return out;
}

json report_json(const detail::ReportData& d) {
  json series = json::array();
  for (const auto& s : d.series) series.push_back(series_json(s));
  return {{"command", "monitor report"},
          {"history", d.file.string()},
          {"total_monitored_s", number_or_null(d.end_s)},
          {"counts",
           {{"runs", d.runs.size()},
            {"series", d.series.size()},
            {"events", d.events.size()},
            {"alarms", d.alarms.size()}}},
          {"runs", runs_json(d)},
          {"series", series},
          {"events", events_json(d.events)},
          {"alarms", alarms_json(d.alarms)}};
}

}  // namespace

void write_monitor_report(const History& h, const std::filesystem::path& out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    throw io::InputError(out_dir.string(), 0, "",
                         "cannot create the report folder: " + ec.message());
  }
  const detail::ReportData d = gather(h);
  report::write_json_file(out_dir / "report.json", report_json(d));
  detail::write_monitor_report_html(d, out_dir / "report.html");
}

}  // namespace rig::monitor
