// rig commission --emulate --clock realtime: a short test paced at 100 Hz on the monotonic
// clock against plantsim integrating in wall time. The report must carry the loop timing
// (lateness of each cycle start against its schedule), and at 100 Hz the 99th percentile of
// that lateness must stay well inside the 10 ms period (< 5 ms).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "tests/integration/commission/run_rig.hpp"

namespace rig::testing {
namespace {

// About 30 s of wall time: 3 s steady state, 5 s pilot, one 1024-sample MMFM block (10-12 s
// of excitation) and its 2 s fade-out, no swept sine.
constexpr const char* kShortRealtimeProfile = R"([steady_state]
duration_s = 3.0
[pilot]
duration_s = 5.0
[mmfm]
block_size = 1024
min_duration_s = 10.0
max_duration_s = 12.0
[sweep]
enabled = false
)";

TEST(RealtimeTiming, ReportCarriesLoopTimingWithP99Below5ms) {
  const auto out = fresh_dir("realtime-timing");
  const auto test = out / "rt.toml";
  std::ofstream(test) << kShortRealtimeProfile;
  const int code = run_rig(fmt::format("commission --emulate --clock realtime --seed 2 --test {} "
                                       "--quiet --out {}",
                                       test.string(), (out / "run").string()),
                           log_beside(out));
  ASSERT_EQ(code, 0) << read_text(log_beside(out));
  const auto report = read_json(out / "run/report.json");
  ASSERT_TRUE(report.contains("loop_timing") && report["loop_timing"].is_object());
  const auto& t = report["loop_timing"];
  const double p50 = t["jitter_p50_ms"], p99 = t["jitter_p99_ms"], max = t["jitter_max_ms"];
  const double test_time_s = report["timing"]["test_time_s"];
  const std::size_t cycles = t["cycles"], overruns = t["overruns"];
  fmt::print(
      "realtime loop at 100 Hz: {} cycles, cycle start late by p50 {:.3f} ms, p99 {:.3f} "
      "ms, max {:.3f} ms, {} overruns, SCHED_FIFO {}, CPUs out of deep idle {}; exchange p50 "
      "{:.3f} ms, p99 {:.3f} "
      "ms, max {:.3f} ms\n",
      cycles, p50, p99, max, overruns, t["realtime_priority"].get<bool>(),
      t["cpu_latency_held"].get<bool>(), t["exchange_p50_ms"].get<double>(),
      t["exchange_p99_ms"].get<double>(), t["exchange_max_ms"].get<double>());
  EXPECT_EQ(t["mode"], "realtime");
  EXPECT_DOUBLE_EQ(t["period_ms"].get<double>(), 10.0);
  EXPECT_EQ(report["config"]["lockstep_ticks"], 0) << "the plant must run on its own clock";
  // One cycle per sample of test time, and the test took as long on the wall clock.
  EXPECT_NEAR(static_cast<double>(cycles), 100.0 * test_time_s, 2.0);
  EXPECT_NEAR(report["timing"]["wall_time_s"].get<double>(), test_time_s, 0.05 * test_time_s + 1.0);
  EXPECT_GE(p50, 0.0);
  EXPECT_LE(p50, p99);
  EXPECT_LE(p99, max);
  EXPECT_LT(p99, 5.0);
  // Overruns depend on the machine's load; a loop overrunning one cycle in ten is broken.
  EXPECT_LT(static_cast<double>(overruns), 0.1 * static_cast<double>(cycles));
  // A slip is a cycle that started more than a period late (after an overrun, or a wake-up
  // the host delayed): no more slips than cycles in the histogram's bins beyond a period.
  const double bin_ms = t["histogram"]["bin_ms"];
  const auto first_late_bin = static_cast<std::size_t>(std::floor(10.0 / bin_ms));
  double histogram_total = 0.0, late_by_a_period = 0.0;
  std::size_t bin = 0;
  for (double c : t["histogram"]["counts"]) {
    histogram_total += c;
    if (bin++ >= first_late_bin) late_by_a_period += c;
  }
  EXPECT_LE(static_cast<double>(t["slips"].get<std::size_t>()), late_by_a_period);
  EXPECT_DOUBLE_EQ(histogram_total, static_cast<double>(cycles));
  const std::string html = read_text(out / "run/report.html");
  EXPECT_NE(html.find("Loop timing"), std::string::npos);
  EXPECT_NE(html.find("Lateness of the cycle start"), std::string::npos);
}

TEST(RealtimeTiming, LockstepRecordsTheWallTimePerExchange) {
  const auto out = fresh_dir("lockstep-timing");
  const auto test = out / "ls.toml";
  std::ofstream(test) << kShortRealtimeProfile;
  const int code = run_rig(fmt::format("commission --emulate --test {} --quiet --out {}",
                                       test.string(), (out / "run").string()),
                           log_beside(out));
  ASSERT_EQ(code, 0) << read_text(log_beside(out));
  const auto t = read_json(out / "run/report.json")["loop_timing"];
  fmt::print(
      "lockstep: {} exchanges, wall time per exchange p50 {:.3f} ms, p99 {:.3f} ms, max "
      "{:.3f} ms\n",
      t["cycles"].get<std::size_t>(), t["exchange_p50_ms"].get<double>(),
      t["exchange_p99_ms"].get<double>(), t["exchange_max_ms"].get<double>());
  EXPECT_EQ(t["mode"], "lockstep");
  EXPECT_FALSE(t.contains("jitter_p99_ms"));
  EXPECT_GT(t["exchange_p50_ms"].get<double>(), 0.0);
  EXPECT_LE(t["exchange_p50_ms"].get<double>(), t["exchange_p99_ms"].get<double>());
  // Lockstep runs faster than real time: an exchange takes well under the 10 ms it simulates.
  EXPECT_LT(t["exchange_p50_ms"].get<double>(), 10.0);
}

}  // namespace
}  // namespace rig::testing
