// The monitor's history (DESIGN.md section 10, issue "condition monitoring"): every estimate,
// residual statistic, event and alarm of every `rig monitor` run, in one embedded SQLite file
// named by --history. Never cleared by the output-directory rules: a restarted monitor appends
// a new run to the same file and its time axis continues where the last run ended.
//
//   History h = History::open("monitor.db");        // creates the schema when new
//   long run = h.begin_run(info);                     // one row in `runs`
//   h.add_values(run, t_s, {{"gain_db", -0.1, lo, hi}, ...});   // one row each in `series`
//   h.add_event(run, t_s, "trip", "power out of band ...");
//   h.add_alarm(run, alarm);
//   h.end_run(run, 0, "stopped by the operator");
//
// Time: `t_s` is the run's own monitor time (plant seconds since the run started); each row
// also stores `history_s` = run offset + t_s, where a run's offset is the previous run's last
// history_s (so trends of several runs line up end to end), and `utc` the wall clock when
// written (ISO 8601). Writes are batched in a transaction committed at least every
// kCommitPeriod rows or by flush(); a kill loses at most the uncommitted rows.
//
// Schema (readable with the sqlite3 command-line client):
//   runs(id INTEGER PRIMARY KEY, started_utc TEXT, ended_utc TEXT, offset_s REAL,
//        link TEXT, baseline TEXT, preset TEXT, seed INTEGER, p0_kw REAL,
//        exit_code INTEGER, outcome TEXT)
//   series(run_id INTEGER, t_s REAL, history_s REAL, utc TEXT, name TEXT, value REAL,
//          lo REAL, hi REAL)        -- lo/hi: the alarm thresholds at that time (NULL: none)
//   events(run_id INTEGER, t_s REAL, history_s REAL, utc TEXT, kind TEXT, text TEXT)
//   alarms(run_id INTEGER, t_s REAL, history_s REAL, utc TEXT, cause TEXT, fault_class TEXT,
//          confidence REAL, onset_s REAL, check_text TEXT, evidence TEXT)  -- evidence: JSON
//   index series(name, history_s); the file is marked by PRAGMA application_id 0x52494748
//   ("RIGH") and PRAGMA user_version 1 (the schema version)
// Errors (cannot open, not a monitor history, disk full) throw HistoryError with one line
// naming the file and what failed.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rig::monitor {

class HistoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RunInfo {
  std::string link;
  std::string baseline;  // the baseline model file
  std::string preset;    // emulated plant preset ("" on a real set)
  long seed = 0;
  double p0_kw = 0.0;
};

struct SeriesValue {
  std::string name;  // e.g. "gain_db", "fn_hz", "zeta", "delay_ms", "parity_z", "line_5hz_kw"
  double value = 0.0;
  std::optional<double> lo;  // alarm thresholds at this time
  std::optional<double> hi;
};

struct AlarmRecord {
  double t_s = 0.0;
  std::string cause;        // physical name, e.g. "injector/cylinder loss"
  std::string fault_class;  // "additive" or "multiplicative"
  double confidence = 0.0;  // 0..1
  double onset_s = 0.0;     // estimated onset (run time)
  std::string check;        // what to check, one sentence
  std::string evidence_json = "{}";
};

struct HistoryRun {
  long id = 0;
  std::string started_utc, ended_utc;
  double offset_s = 0.0;
  RunInfo info;
  std::optional<int> exit_code;
  std::string outcome;
};

struct HistoryPoint {
  long run_id = 0;
  double t_s = 0.0, history_s = 0.0;
  std::string utc;
  double value = 0.0;
  std::optional<double> lo, hi;
};

struct HistoryEvent {
  long run_id = 0;
  double t_s = 0.0, history_s = 0.0;
  std::string utc, kind, text;
};

struct HistoryAlarm {
  long run_id = 0;
  double history_s = 0.0;
  std::string utc;
  AlarmRecord alarm;
};

// Counts and extremes of one whole series (not decimated), for the report's summary.
struct SeriesSummary {
  std::size_t count = 0;
  double first_history_s = 0.0, last_history_s = 0.0;
  std::optional<double> min, max;  // none when every value is NaN
};

class History {
 public:
  static constexpr int kCommitPeriod = 200;
  // Opens (creating the schema when the file is new) or throws HistoryError.
  static History open(const std::filesystem::path& file);
  // Opens an existing history read-only (for --report); throws when missing or not a history.
  static History open_read_only(const std::filesystem::path& file);
  History(History&&) noexcept;
  History& operator=(History&&) noexcept;
  ~History();  // commits what is pending

  long begin_run(const RunInfo& info);
  void add_values(long run, double t_s, const std::vector<SeriesValue>& values);
  void add_event(long run, double t_s, const std::string& kind, const std::string& text);
  void add_alarm(long run, const AlarmRecord& alarm);
  void end_run(long run, int exit_code, const std::string& outcome);
  // The run's first steady-state P0, once measured (a run starts before it is known).
  void set_run_p0(long run, double p0_kw);
  void flush();  // commits pending rows

  // Reading (for the report and tests).
  std::vector<HistoryRun> runs() const;
  std::vector<std::string> series_names() const;
  // Points of one series in history order; at most max_points, evenly decimated (keeping the
  // first and last) so that months of history draw quickly.
  std::vector<HistoryPoint> series(const std::string& name, std::size_t max_points = 20000) const;
  SeriesSummary series_summary(const std::string& name) const;
  std::vector<HistoryEvent> events() const;
  std::vector<HistoryAlarm> alarms() const;
  const std::filesystem::path& file() const;

 private:
  struct Impl;
  explicit History(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rig::monitor
