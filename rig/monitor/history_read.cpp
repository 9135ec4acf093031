// Reading a monitor history: runs, series (decimated), events and alarms.
#include <algorithm>

#include "rig/monitor/history_impl.hpp"

namespace rig::monitor {

using namespace history_detail;

std::vector<HistoryRun> History::runs() const {
  const StmtPtr s = impl_->prepare(
      "SELECT id, started_utc, ended_utc, offset_s, link, baseline, preset, seed, p0_kw, "
      "exit_code, outcome FROM runs ORDER BY id");
  std::vector<HistoryRun> out;
  while (impl_->step_read(s.get())) {
    sqlite3_stmt* r = s.get();
    HistoryRun run;
    run.id = static_cast<long>(sqlite3_column_int64(r, 0));
    run.started_utc = column_text(r, 1);
    run.ended_utc = column_text(r, 2);
    run.offset_s = column_double(r, 3);
    run.info = {column_text(r, 4), column_text(r, 5), column_text(r, 6),
                static_cast<long>(sqlite3_column_int64(r, 7)), column_double(r, 8)};
    if (sqlite3_column_type(r, 9) != SQLITE_NULL) run.exit_code = sqlite3_column_int(r, 9);
    run.outcome = column_text(r, 10);
    out.push_back(std::move(run));
  }
  return out;
}

std::vector<std::string> History::series_names() const {
  const std::string sql =
      std::string(kNamesCte) + "SELECT name FROM names WHERE name IS NOT NULL ORDER BY name";
  const StmtPtr s = impl_->prepare(sql.c_str());
  std::vector<std::string> out;
  while (impl_->step_read(s.get())) out.push_back(column_text(s.get(), 0));
  return out;
}

SeriesSummary History::series_summary(const std::string& name) const {
  const StmtPtr s = impl_->prepare(
      "SELECT COUNT(*), MIN(history_s), MAX(history_s), MIN(value), MAX(value) FROM series "
      "WHERE name = ?");
  bind(s.get(), 1, name);
  SeriesSummary out;
  if (!impl_->step_read(s.get())) return out;
  out.count = static_cast<std::size_t>(sqlite3_column_int64(s.get(), 0));
  if (out.count == 0) return out;
  out.first_history_s = column_double(s.get(), 1);
  out.last_history_s = column_double(s.get(), 2);
  out.min = column_optional(s.get(), 3);
  out.max = column_optional(s.get(), 4);
  return out;
}

// Row i of n is kept when it is the k-th of max_points evenly spaced indices
// round(k (n - 1) / (max_points - 1)): the first and the last are always kept.
std::vector<HistoryPoint> History::series(const std::string& name, std::size_t max_points) const {
  const std::size_t n = series_summary(name).count;
  std::vector<HistoryPoint> out;
  if (n == 0 || max_points == 0) return out;
  const std::size_t m = std::min(n, max_points);
  const auto wanted = [&](std::size_t k) {
    return m == 1 ? 0 : (k * (n - 1) + (m - 1) / 2) / (m - 1);
  };
  const StmtPtr s = impl_->prepare(
      "SELECT run_id, t_s, history_s, utc, value, lo, hi FROM series WHERE name = ? "
      "ORDER BY history_s, rowid");
  bind(s.get(), 1, name);
  out.reserve(m);
  std::size_t next = wanted(0);
  for (std::size_t i = 0; out.size() < m && impl_->step_read(s.get()); ++i) {
    if (i != next) continue;
    sqlite3_stmt* r = s.get();
    out.push_back({static_cast<long>(sqlite3_column_int64(r, 0)), column_double(r, 1),
                   column_double(r, 2), column_text(r, 3), column_double(r, 4),
                   column_optional(r, 5), column_optional(r, 6)});
    next = wanted(out.size());
  }
  return out;
}

std::vector<HistoryEvent> History::events() const {
  const StmtPtr s = impl_->prepare(
      "SELECT run_id, t_s, history_s, utc, kind, text FROM events ORDER BY history_s, rowid");
  std::vector<HistoryEvent> out;
  while (impl_->step_read(s.get())) {
    sqlite3_stmt* r = s.get();
    out.push_back({static_cast<long>(sqlite3_column_int64(r, 0)), column_double(r, 1),
                   column_double(r, 2), column_text(r, 3), column_text(r, 4), column_text(r, 5)});
  }
  return out;
}

std::vector<HistoryAlarm> History::alarms() const {
  const StmtPtr s = impl_->prepare(
      "SELECT run_id, t_s, history_s, utc, cause, fault_class, confidence, onset_s, check_text, "
      "evidence FROM alarms ORDER BY history_s, rowid");
  std::vector<HistoryAlarm> out;
  while (impl_->step_read(s.get())) {
    sqlite3_stmt* r = s.get();
    HistoryAlarm a;
    a.run_id = static_cast<long>(sqlite3_column_int64(r, 0));
    a.alarm.t_s = column_double(r, 1);
    a.history_s = column_double(r, 2);
    a.utc = column_text(r, 3);
    a.alarm.cause = column_text(r, 4);
    a.alarm.fault_class = column_text(r, 5);
    a.alarm.confidence = column_double(r, 6);
    a.alarm.onset_s = column_double(r, 7);
    a.alarm.check = column_text(r, 8);
    a.alarm.evidence_json = column_text(r, 9);
    out.push_back(std::move(a));
  }
  return out;
}

}  // namespace rig::monitor
