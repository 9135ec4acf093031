// The monitor history file: runs appended end to end, batching, decimation, refusal of
// foreign files, and readability by the independent sqlite3 command-line client.
#include "rig/monitor/history.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include "tests/unit/monitor/test_dir.hpp"

namespace rig::monitor {
namespace {

RunInfo info(long seed) { return {"sim://", "baseline.json", "nominal", seed, 400.0}; }

AlarmRecord alarm(double t_s) {
  return {t_s,        "injector/cylinder loss", "additive",    0.93,
          t_s - 20.0, "Check the injectors.",   R"({"z":4.2})"};
}

// Values every 10 s from 0 to end_s: gain_db with thresholds, fn_hz without.
void write_values(History& h, long run, double end_s) {
  for (double t = 0.0; t <= end_s; t += 10.0) {
    h.add_values(run, t, {{"gain_db", -0.01 * t, -1.0, 1.0}, {"fn_hz", 1.2, {}, {}}});
  }
}

void expect_one_line_naming(const HistoryError& e, const std::filesystem::path& file) {
  const std::string what = e.what();
  EXPECT_NE(what.find(file.string()), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

TEST(History, SecondRunContinuesTheTimeAxisAndKeepsTheFirstRunsRows) {
  TempDir dir;
  const auto file = dir / "monitor.db";
  {
    History h = History::open(file);
    const long run = h.begin_run(info(1));
    write_values(h, run, 100.0);
    h.add_event(run, 50.0, "trip", "power out of band");
    h.add_alarm(run, alarm(60.0));
    h.end_run(run, 3, "tripped");
  }
  {
    History h = History::open(file);
    ASSERT_EQ(h.runs().size(), 1u);
    const long run = h.begin_run(info(2));
    write_values(h, run, 50.0);
    h.add_alarm(run, alarm(30.0));
  }  // not ended: the destructor commits
  const History h = History::open_read_only(file);
  const auto runs = h.runs();
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_DOUBLE_EQ(runs[0].offset_s, 0.0);
  EXPECT_DOUBLE_EQ(runs[1].offset_s, 100.0);
  EXPECT_EQ(runs[0].exit_code, 3);
  EXPECT_EQ(runs[0].outcome, "tripped");
  EXPECT_FALSE(runs[0].ended_utc.empty());
  EXPECT_FALSE(runs[1].exit_code.has_value());
  EXPECT_EQ(runs[1].info.seed, 2);
  EXPECT_EQ(h.series_names(), (std::vector<std::string>{"fn_hz", "gain_db"}));
  const auto gain = h.series("gain_db");
  ASSERT_EQ(gain.size(), 11u + 6u);
  EXPECT_EQ(gain.front().run_id, runs[0].id);
  EXPECT_DOUBLE_EQ(gain[10].history_s, 100.0);
  EXPECT_EQ(gain[11].run_id, runs[1].id);
  EXPECT_DOUBLE_EQ(gain[11].t_s, 0.0);
  EXPECT_DOUBLE_EQ(gain[11].history_s, 100.0);
  EXPECT_DOUBLE_EQ(gain.back().history_s, 150.0);
  EXPECT_EQ(gain.front().lo, -1.0);
  EXPECT_FALSE(h.series("fn_hz").front().hi.has_value());
  const auto alarms = h.alarms();
  ASSERT_EQ(alarms.size(), 2u);
  EXPECT_DOUBLE_EQ(alarms[0].history_s, 60.0);
  EXPECT_DOUBLE_EQ(alarms[1].history_s, 130.0);
  EXPECT_EQ(alarms[1].alarm.cause, "injector/cylinder loss");
  EXPECT_EQ(alarms[1].alarm.evidence_json, R"({"z":4.2})");
  ASSERT_EQ(h.events().size(), 1u);
  EXPECT_EQ(h.events()[0].kind, "trip");
  const auto summary = h.series_summary("gain_db");
  EXPECT_EQ(summary.count, 17u);
  EXPECT_DOUBLE_EQ(summary.last_history_s, 150.0);
  EXPECT_DOUBLE_EQ(*summary.min, -1.0);
}

TEST(History, RowsAreCommittedEveryCommitPeriodAndOnFlush) {
  TempDir dir;
  const auto file = dir / "monitor.db";
  History h = History::open(file);
  const long run = h.begin_run(info(1));
  for (int i = 0; i < History::kCommitPeriod + 5; ++i) h.add_values(run, i, {{"x", 1.0 * i}});
  // Another connection sees the committed rows only.
  EXPECT_EQ(History::open_read_only(file).series_summary("x").count,
            static_cast<std::size_t>(History::kCommitPeriod));
  h.flush();
  EXPECT_EQ(History::open_read_only(file).series_summary("x").count,
            static_cast<std::size_t>(History::kCommitPeriod + 5));
}

TEST(History, AKilledMonitorLeavesItsCommittedRows) {
  TempDir dir;
  const auto file = dir / "monitor.db";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    History h = History::open(file);
    const long run = h.begin_run(info(1));
    for (int i = 0; i < 2 * History::kCommitPeriod + 50; ++i) h.add_values(run, i, {{"x", 1.0}});
    ::_exit(0);  // no destructor: as if killed
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  const History h = History::open_read_only(file);
  ASSERT_EQ(h.runs().size(), 1u);
  EXPECT_TRUE(h.runs()[0].ended_utc.empty());
  EXPECT_GE(h.series_summary("x").count, static_cast<std::size_t>(2 * History::kCommitPeriod));
}

TEST(History, DecimationKeepsFirstAndLastAndCapsTheCount) {
  TempDir dir;
  History h = History::open(dir / "monitor.db");
  const long run = h.begin_run(info(1));
  const int n = 1001;
  for (int i = 0; i < n; ++i) h.add_values(run, i, {{"x", 2.0 * i}});
  const auto all = h.series("x");
  EXPECT_EQ(all.size(), static_cast<std::size_t>(n));
  const auto few = h.series("x", 100);
  ASSERT_EQ(few.size(), 100u);
  EXPECT_DOUBLE_EQ(few.front().t_s, 0.0);
  EXPECT_DOUBLE_EQ(few.back().t_s, n - 1.0);
  for (std::size_t i = 1; i < few.size(); ++i) {
    const double step = few[i].t_s - few[i - 1].t_s;
    EXPECT_GE(step, 10.0) << i;  // evenly: 1000 / 99 = 10.1 rows apart
    EXPECT_LE(step, 11.0) << i;
    EXPECT_DOUBLE_EQ(few[i].value, 2.0 * few[i].t_s);
  }
  EXPECT_EQ(h.series("x", 2).size(), 2u);
  EXPECT_DOUBLE_EQ(h.series("x", 2).back().t_s, n - 1.0);
  EXPECT_EQ(h.series("x", 1).size(), 1u);
  EXPECT_TRUE(h.series("x", 0).empty());
  EXPECT_TRUE(h.series("missing").empty());
}

TEST(History, NanValuesAndMissingThresholdsReadBack) {
  TempDir dir;
  History h = History::open(dir / "monitor.db");
  const long run = h.begin_run(info(1));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  h.add_values(run, 1.0, {{"zeta", nan, std::nullopt, 0.5}, {"zeta", 0.2, nan, 0.5}});
  const auto p = h.series("zeta");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_TRUE(std::isnan(p[0].value));
  EXPECT_FALSE(p[0].lo.has_value());
  EXPECT_EQ(p[0].hi, 0.5);
  EXPECT_FALSE(p[1].lo.has_value());
  EXPECT_FALSE(p[0].utc.empty());
  EXPECT_THROW(h.add_values(run, nan, {{"zeta", 0.1}}), HistoryError);
  EXPECT_THROW(h.add_values(run + 7, 2.0, {{"zeta", 0.1}}), HistoryError);
  EXPECT_THROW(h.end_run(run + 7, 0, "x"), HistoryError);
}

TEST(History, RefusesAnotherSqliteFileNamingIt) {
  TempDir dir;
  const auto file = dir / "other.db";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "CREATE TABLE foo(a); INSERT INTO foo VALUES(1);", nullptr, nullptr,
                         nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  for (bool read_only : {false, true}) {
    try {
      read_only ? History::open_read_only(file) : History::open(file);
      ADD_FAILURE() << "a foreign SQLite file was accepted";
    } catch (const HistoryError& e) {
      expect_one_line_naming(e, file);
      EXPECT_NE(std::string(e.what()).find("not a monitor history"), std::string::npos);
    }
  }
  // Left as it was: no history tables added.
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  int tables = -1;
  sqlite3_exec(
      db, "SELECT COUNT(*) FROM sqlite_master",
      [](void* out, int, char** v, char**) { return *static_cast<int*>(out) = std::atoi(v[0]), 0; },
      &tables, nullptr);
  sqlite3_close(db);
  EXPECT_EQ(tables, 1);
}

TEST(History, RefusesATextFileNamingIt) {
  TempDir dir;
  const auto file = dir / "notes.txt";
  const std::string text(2000, 'x');
  std::ofstream(file) << text;
  for (bool read_only : {false, true}) {
    try {
      read_only ? History::open_read_only(file) : History::open(file);
      ADD_FAILURE() << "a text file was accepted";
    } catch (const HistoryError& e) {
      expect_one_line_naming(e, file);
      EXPECT_NE(std::string(e.what()).find("not a monitor history"), std::string::npos);
    }
  }
  std::ifstream in(file);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), text);
}

TEST(History, ReadOnlyOpeningNeedsAnExistingHistoryAndRefusesWrites) {
  TempDir dir;
  const auto file = dir / "monitor.db";
  try {
    History::open_read_only(file);
    ADD_FAILURE() << "a missing file was accepted";
  } catch (const HistoryError& e) {
    expect_one_line_naming(e, file);
  }
  EXPECT_FALSE(std::filesystem::exists(file));
  History::open(file).begin_run(info(1));
  History h = History::open_read_only(file);
  EXPECT_EQ(h.runs().size(), 1u);
  EXPECT_THROW(h.begin_run(info(2)), HistoryError);
  EXPECT_THROW(h.add_values(1, 0.0, {{"x", 1.0}}), HistoryError);
  EXPECT_NO_THROW(h.flush());
}

// A write failing on the disk (here: the file-size limit) throws a HistoryError naming the
// file; what was committed before stays readable.
TEST(History, AWriteFailureThrowsNamingTheFile) {
  TempDir dir;
  const auto file = dir / "monitor.db";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    History h = History::open(file);
    const long run = h.begin_run(info(1));
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{256 * 1024, 256 * 1024};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try {
      for (int i = 0; i < 100000; ++i) h.add_values(run, i, {{"x", 1.0 * i, 0.0, 2.0}});
    } catch (const HistoryError& e) {
      std::fprintf(stderr, "%s\n", e.what());
      ::_exit(std::string(e.what()).find(file.string()) == 0 ? 0 : 2);
    }
    ::_exit(1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: no error thrown, 2: the message does not name the file";
  const History h = History::open_read_only(file);
  EXPECT_EQ(h.runs().size(), 1u);
  EXPECT_GT(h.series_summary("x").count, 0u);
}

std::string find_in_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string d; std::getline(dirs, d, ':');) {
    const auto candidate = std::filesystem::path(d.empty() ? "." : d) / program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return "";
}

std::string run(const std::string& command) {
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen(command.c_str(), "r"), ::pclose);
  if (!pipe) return out;
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe.get())) > 0)
    out.append(buffer.data(), n);
  return out;
}

TEST(History, TheSqlite3CommandLineClientReadsTheAlarms) {
  const std::string client = find_in_path("sqlite3");
  if (client.empty()) GTEST_SKIP() << "no sqlite3 command-line client in PATH";
  TempDir dir;
  const auto file = dir / "monitor.db";
  History h = History::open(file);
  const long run_id = h.begin_run(info(1));
  write_values(h, run_id, 30.0);
  h.add_alarm(run_id, alarm(25.0));
  h.flush();
  // While the monitor still has the file open.
  const std::string out = run(client + " -readonly -separator '|' '" + file.string() +
                              "' 'SELECT run_id, cause, fault_class, confidence FROM alarms;' "
                              "2>&1");
  EXPECT_EQ(out, std::to_string(run_id) + "|injector/cylinder loss|additive|0.93\n");
  const std::string count =
      run(client + " -readonly '" + file.string() + "' 'SELECT COUNT(*) FROM series;' 2>&1");
  EXPECT_EQ(count, "8\n");  // 4 times, 2 series
}

}  // namespace
}  // namespace rig::monitor
