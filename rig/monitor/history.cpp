#include "rig/monitor/history.hpp"

#include <fmt/format.h>
#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <map>
#include <string_view>

#include "rig/monitor/history_impl.hpp"

namespace rig::monitor {
namespace {

// Marks the file as a monitor history (`PRAGMA application_id`, also shown by file(1)); the
// schema version is `PRAGMA user_version`.
constexpr int kApplicationId = 0x52494748;  // "RIGH"
constexpr int kSchemaVersion = 1;
constexpr int kBusyTimeoutMs = 5000;

constexpr const char* kSchema = R"sql(
CREATE TABLE runs(id INTEGER PRIMARY KEY, started_utc TEXT, ended_utc TEXT, offset_s REAL,
                  link TEXT, baseline TEXT, preset TEXT, seed INTEGER, p0_kw REAL,
                  exit_code INTEGER, outcome TEXT);
CREATE TABLE series(run_id INTEGER, t_s REAL, history_s REAL, utc TEXT, name TEXT, value REAL,
                    lo REAL, hi REAL);
CREATE TABLE events(run_id INTEGER, t_s REAL, history_s REAL, utc TEXT, kind TEXT, text TEXT);
CREATE TABLE alarms(run_id INTEGER, t_s REAL, history_s REAL, utc TEXT, cause TEXT,
                    fault_class TEXT, confidence REAL, onset_s REAL, check_text TEXT,
                    evidence TEXT);
CREATE INDEX series_name_history ON series(name, history_s);
PRAGMA application_id = 1380534088;
PRAGMA user_version = 1;
)sql";
static_assert(kApplicationId == 1380534088);

std::string utc_now() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  ::gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &tm);
  return fmt::format("{}.{:03d}Z", text, static_cast<int>(ms));
}

}  // namespace

using namespace history_detail;

int History::Impl::pragma(const char* sql) const {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &raw, nullptr) != SQLITE_OK) {
    if (sqlite3_errcode(db) == SQLITE_NOTADB) not_a_history(sqlite3_errmsg(db));
    fail("cannot read");
  }
  StmtPtr s(raw, sqlite3_finalize);
  const int rc = sqlite3_step(s.get());
  if (rc == SQLITE_NOTADB) not_a_history(sqlite3_errmsg(db));
  if (rc != SQLITE_ROW) fail("cannot read");
  return sqlite3_column_int(s.get(), 0);
}

// A file with our application_id is a history; an empty database (a new file) becomes one
// when opened for writing; anything else is refused.
void History::Impl::recognise() {
  if (!read_only) exec("BEGIN IMMEDIATE", "cannot open for writing");
  const int tables = pragma("SELECT COUNT(*) FROM sqlite_master");
  const int app = pragma("PRAGMA application_id");
  const int version = pragma("PRAGMA user_version");
  if (app == kApplicationId && version > kSchemaVersion) {
    throw HistoryError(
        fmt::format("{}: written by a newer rig (history schema {}, this rig reads "
                    "up to {})",
                    file.string(), version, kSchemaVersion));
  }
  if (app != kApplicationId && (tables > 0 || app != 0 || read_only)) {
    not_a_history(tables > 0 ? fmt::format("a SQLite database with {} other tables or indices "
                                           "and no monitor history mark (application_id)",
                                           tables)
                             : std::string("an empty SQLite database"));
  }
  if (app != kApplicationId) exec(kSchema, "cannot create the history tables");
  if (!read_only) exec("COMMIT", "cannot create the history tables");
  recognised = true;
}

void History::Impl::prepare_writing() {
  // WAL: a report or the sqlite3 client can read while the monitor writes; a killed monitor
  // loses only the rows not yet committed.
  exec("PRAGMA journal_mode = WAL", "cannot set the journal mode");
  exec("PRAGMA synchronous = NORMAL", "cannot set the synchronous mode");
  insert_series = prepare(
      "INSERT INTO series(run_id, t_s, history_s, utc, name, value, lo, hi) "
      "VALUES(?, ?, ?, ?, ?, ?, ?, ?)");
  insert_event = prepare(
      "INSERT INTO events(run_id, t_s, history_s, utc, kind, text) VALUES(?, ?, ?, ?, ?, ?)");
  insert_alarm = prepare(
      "INSERT INTO alarms(run_id, t_s, history_s, utc, cause, fault_class, confidence, onset_s, "
      "check_text, evidence) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
}

double History::Impl::offset_of(long run, double t_s) {
  writable();
  if (!std::isfinite(t_s)) {
    throw HistoryError(
        fmt::format("{}: run {}: the time {} is not finite", file.string(), run, t_s));
  }
  if (const auto it = offsets.find(run); it != offsets.end()) return it->second;
  const StmtPtr s = prepare("SELECT offset_s FROM runs WHERE id = ?");
  bind(s.get(), 1, run);
  if (!step_read(s.get())) {
    throw HistoryError(fmt::format("{}: no run {} in this history", file.string(), run));
  }
  return offsets[run] = sqlite3_column_double(s.get(), 0);
}

// The largest history time written so far (0 when empty): where the next run starts.
double History::Impl::history_end() const {
  const std::string sql = std::string(kNamesCte) + R"sql(
SELECT MAX(m) FROM (
  SELECT (SELECT MAX(history_s) FROM series WHERE series.name = names.name) AS m
    FROM names WHERE names.name IS NOT NULL
  UNION ALL SELECT MAX(history_s) FROM events
  UNION ALL SELECT MAX(history_s) FROM alarms
  UNION ALL SELECT MAX(offset_s) FROM runs))sql";
  const StmtPtr s = prepare(sql.c_str());
  if (!step_read(s.get()) || sqlite3_column_type(s.get(), 0) == SQLITE_NULL) return 0.0;
  return sqlite3_column_double(s.get(), 0);
}

std::unique_ptr<History::Impl> History::Impl::open(const std::filesystem::path& file,
                                                   bool read_only) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw HistoryError(file.string() + ": a folder, expected a monitor history file");
  }
  if (read_only && !std::filesystem::exists(file, ec)) {
    throw HistoryError(file.string() + ": cannot open the monitor history: no such file");
  }
  auto impl = std::make_unique<Impl>();
  impl->file = file;
  impl->read_only = read_only;
  const int flags = read_only ? SQLITE_OPEN_READONLY : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  if (sqlite3_open_v2(file.c_str(), &impl->db, flags, nullptr) != SQLITE_OK) {
    impl->fail("cannot open the monitor history");
  }
  sqlite3_busy_timeout(impl->db, kBusyTimeoutMs);
  if (!read_only && sqlite3_db_readonly(impl->db, "main") == 1) {
    throw HistoryError(file.string() +
                       ": cannot open the monitor history for writing: the "
                       "file is read-only");
  }
  impl->recognise();
  if (!read_only) impl->prepare_writing();
  return impl;
}

History History::open(const std::filesystem::path& file) {
  return History(Impl::open(file, false));
}
History History::open_read_only(const std::filesystem::path& file) {
  return History(Impl::open(file, true));
}
History::History(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
History::History(History&&) noexcept = default;
History& History::operator=(History&&) noexcept = default;
History::~History() = default;  // Impl commits what is pending
const std::filesystem::path& History::file() const { return impl_->file; }

long History::begin_run(const RunInfo& info) {
  Impl& m = *impl_;
  m.writable();
  m.commit();
  const double offset = m.history_end();
  const StmtPtr s = m.prepare(
      "INSERT INTO runs(started_utc, offset_s, link, baseline, preset, seed, p0_kw) "
      "VALUES(?, ?, ?, ?, ?, ?, ?)");
  bind(s.get(), 1, utc_now());
  bind(s.get(), 2, offset);
  bind(s.get(), 3, info.link);
  bind(s.get(), 4, info.baseline);
  bind(s.get(), 5, info.preset);
  bind(s.get(), 6, info.seed);
  bind(s.get(), 7, info.p0_kw);
  m.step_write(s.get(), "cannot add a run");
  const long id = static_cast<long>(sqlite3_last_insert_rowid(m.db));
  m.offsets[id] = offset;
  return id;
}

void History::add_values(long run, double t_s, const std::vector<SeriesValue>& values) {
  Impl& m = *impl_;
  const double history_s = m.offset_of(run, t_s) + t_s;
  const std::string utc = utc_now();
  m.begin();
  sqlite3_stmt* s = m.insert_series.get();
  for (const SeriesValue& v : values) {
    bind(s, 1, run);
    bind(s, 2, t_s);
    bind(s, 3, history_s);
    bind(s, 4, utc);
    bind(s, 5, v.name);
    bind(s, 6, v.value);
    bind(s, 7, v.lo);
    bind(s, 8, v.hi);
    m.step_write(s, "cannot write a value");
    ++m.pending;
  }
  m.commit_when_due();
}

// Events and alarms are rare and matter most after a kill: committed at once.
void History::add_event(long run, double t_s, const std::string& kind, const std::string& text) {
  Impl& m = *impl_;
  const double history_s = m.offset_of(run, t_s) + t_s;
  m.begin();
  sqlite3_stmt* s = m.insert_event.get();
  bind(s, 1, run);
  bind(s, 2, t_s);
  bind(s, 3, history_s);
  bind(s, 4, utc_now());
  bind(s, 5, kind);
  bind(s, 6, text);
  m.step_write(s, "cannot write an event");
  m.commit();
}

void History::add_alarm(long run, const AlarmRecord& a) {
  Impl& m = *impl_;
  const double history_s = m.offset_of(run, a.t_s) + a.t_s;
  m.begin();
  sqlite3_stmt* s = m.insert_alarm.get();
  bind(s, 1, run);
  bind(s, 2, a.t_s);
  bind(s, 3, history_s);
  bind(s, 4, utc_now());
  bind(s, 5, a.cause);
  bind(s, 6, a.fault_class);
  bind(s, 7, a.confidence);
  bind(s, 8, a.onset_s);
  bind(s, 9, a.check);
  bind(s, 10, a.evidence_json);
  m.step_write(s, "cannot write an alarm");
  m.commit();
}

void History::end_run(long run, int exit_code, const std::string& outcome) {
  Impl& m = *impl_;
  m.offset_of(run, 0.0);
  m.begin();
  const StmtPtr s =
      m.prepare("UPDATE runs SET ended_utc = ?, exit_code = ?, outcome = ? WHERE id = ?");
  bind(s.get(), 1, utc_now());
  bind(s.get(), 2, static_cast<long>(exit_code));
  bind(s.get(), 3, outcome);
  bind(s.get(), 4, run);
  m.step_write(s.get(), "cannot end the run");
  m.commit();
}

void History::set_run_p0(long run, double p0_kw) {
  Impl& m = *impl_;
  m.offset_of(run, 0.0);
  m.begin();
  const StmtPtr s = m.prepare("UPDATE runs SET p0_kw = ? WHERE id = ?");
  bind(s.get(), 1, p0_kw);
  bind(s.get(), 2, run);
  m.step_write(s.get(), "cannot record the run's P0");
  m.commit();
}

void History::flush() {
  if (!impl_->read_only) impl_->commit();
}

}  // namespace rig::monitor
