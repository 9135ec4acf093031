// The state behind a History (internal to rig/monitor/history*.cpp): the SQLite connection,
// the prepared insert statements and the pending transaction.
#pragma once

#include <fmt/format.h>
#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <string_view>

#include "rig/monitor/history.hpp"

namespace rig::monitor {
namespace history_detail {

// Besides every kCommitPeriod rows, pending rows are committed once they are this old (wall
// clock), so that a slow monitor does not keep minutes of history uncommitted.
inline constexpr double kMaxUncommittedS = 10.0;

// The distinct series names, each found through the index (a skip scan that does not read
// every row of a long history).
inline constexpr const char* kNamesCte = R"sql(
WITH RECURSIVE names(name) AS (
  SELECT MIN(name) FROM series
  UNION ALL
  SELECT (SELECT MIN(name) FROM series WHERE name > names.name) FROM names
  WHERE names.name IS NOT NULL)
)sql";

using StmtPtr = std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)>;

inline void bind(sqlite3_stmt* s, int i, double v) {
  if (std::isnan(v)) {
    sqlite3_bind_null(s, i);
  } else {
    sqlite3_bind_double(s, i, v);
  }
}
inline void bind(sqlite3_stmt* s, int i, const std::optional<double>& v) {
  bind(s, i, v ? *v : std::numeric_limits<double>::quiet_NaN());
}
inline void bind(sqlite3_stmt* s, int i, const std::string& v) {
  sqlite3_bind_text(s, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
}
inline void bind(sqlite3_stmt* s, int i, long v) { sqlite3_bind_int64(s, i, v); }

// NULL (a NaN when written) reads back as NaN, not as sqlite's 0.0.
inline double column_double(sqlite3_stmt* s, int i) {
  return sqlite3_column_type(s, i) == SQLITE_NULL ? std::numeric_limits<double>::quiet_NaN()
                                                  : sqlite3_column_double(s, i);
}
inline std::optional<double> column_optional(sqlite3_stmt* s, int i) {
  if (sqlite3_column_type(s, i) == SQLITE_NULL) return std::nullopt;
  return sqlite3_column_double(s, i);
}
inline std::string column_text(sqlite3_stmt* s, int i) {
  const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(s, i));
  return text ? std::string(text, static_cast<std::size_t>(sqlite3_column_bytes(s, i))) : "";
}

}  // namespace history_detail

struct History::Impl {
  std::filesystem::path file;
  sqlite3* db = nullptr;
  bool read_only = false;
  bool recognised = false;  // until then an open transaction is rolled back, not committed
  history_detail::StmtPtr insert_series{nullptr, sqlite3_finalize};
  history_detail::StmtPtr insert_event{nullptr, sqlite3_finalize};
  history_detail::StmtPtr insert_alarm{nullptr, sqlite3_finalize};
  int pending = 0;
  std::chrono::steady_clock::time_point transaction_began;
  std::map<long, double> offsets;  // run id -> offset_s

  ~Impl() {
    if (db && !sqlite3_get_autocommit(db)) {
      if (!recognised) {
        sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
      } else if (sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK) {
        std::fprintf(stderr, "%s: cannot commit the last rows: %s\n", file.c_str(),
                     sqlite3_errmsg(db));
      }
    }
    // Back to a single file once closed (readable from a read-only folder and copied as one
    // file); fails harmlessly while a reader still has the file open.
    if (db && recognised && !read_only) {
      sqlite3_exec(db, "PRAGMA journal_mode = DELETE", nullptr, nullptr, nullptr);
    }
    insert_series.reset();
    insert_event.reset();
    insert_alarm.reset();
    sqlite3_close_v2(db);
  }

  [[noreturn]] void fail(std::string_view what) const {
    throw HistoryError(
        fmt::format("{}: {}: {}", file.string(), what, db ? sqlite3_errmsg(db) : "out of memory"));
  }
  [[noreturn]] void not_a_history(std::string_view why) const {
    throw HistoryError(
        fmt::format("{}: not a monitor history (expected a SQLite file written by rig monitor): {}",
                    file.string(), why));
  }

  history_detail::StmtPtr prepare(const char* sql) const {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) != SQLITE_OK) fail("cannot read");
    return history_detail::StmtPtr(s, sqlite3_finalize);
  }
  void exec(const char* sql, std::string_view what) {
    if (sqlite3_exec(db, sql, nullptr, nullptr, nullptr) != SQLITE_OK) written(false, what);
  }
  // After a write: on failure sqlite may have rolled the transaction back, so the count of
  // pending rows follows it before the error is thrown.
  void written(bool ok, std::string_view what) {
    if (ok) return;
    if (sqlite3_get_autocommit(db)) pending = 0;
    if (sqlite3_errcode(db) == SQLITE_NOTADB) not_a_history(sqlite3_errmsg(db));
    fail(what);
  }
  void step_write(sqlite3_stmt* s, std::string_view what) {
    const int rc = sqlite3_step(s);
    sqlite3_reset(s);
    written(rc == SQLITE_DONE, what);
  }
  bool step_read(sqlite3_stmt* s) const {
    const int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) return true;
    if (rc != SQLITE_DONE) fail("cannot read");
    return false;
  }

  void writable() const {
    if (read_only) throw HistoryError(file.string() + ": opened read-only, cannot write");
  }
  void begin() {
    if (!sqlite3_get_autocommit(db)) return;
    exec("BEGIN", "cannot write");
    transaction_began = std::chrono::steady_clock::now();
  }
  void commit() {
    if (!sqlite3_get_autocommit(db)) exec("COMMIT", "cannot commit");
    pending = 0;
  }
  void commit_when_due() {
    const std::chrono::duration<double> age = std::chrono::steady_clock::now() - transaction_began;
    if (pending >= kCommitPeriod || age.count() >= history_detail::kMaxUncommittedS) commit();
  }

  static std::unique_ptr<Impl> open(const std::filesystem::path& file, bool read_only);
  int pragma(const char* sql) const;
  void recognise();
  void prepare_writing();
  double offset_of(long run, double t_s);
  double history_end() const;
};

}  // namespace rig::monitor
