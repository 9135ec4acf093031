// rig identify with separate records (seed 001's practice): estimate on one commissioning
// recording, choose the structure on a second, and check the choice on a third that took no
// part in either. Three emulated commissioning tests of the same plant at the same load,
// noise seeds 1, 2 and 3. Also: the dead time refers to the plant (sidecar
// y_sampled_after_s), as rig commission's model does; several estimation records; and the
// one-line errors of records that do not go together.
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace rig::testing {
namespace {

using nlohmann::json;

// The promise of the table's rule: the structure chosen on B scores within this of the best on C.
constexpr double kChoiceMarginPct = 1.0;
// Two estimates of the same plant's dead time from the same rows: rig commission's online
// MMFM+OE and rig identify's table agree to a tenth of a sample (0.01 s).
constexpr double kDelayAgreementS = 0.001;

// The three runs, made once for every test of this file (ctest runs each in its own
// process, two at a time): in a folder named after this rig binary's build time, made under
// a lock, complete when its marker exists.
const std::filesystem::path& runs_dir() {
  static const std::filesystem::path dir = [] {
    const auto built = std::filesystem::last_write_time(rig_binary()).time_since_epoch().count();
    const auto tmp = std::filesystem::temp_directory_path();
    const auto d = tmp / fmt::format("rig_identify_fit_table_runs_{}", built);
    // An earlier build's runs are stale: removed, so that the folders do not pile up.
    std::error_code ignored;
    for (const auto& e : std::filesystem::directory_iterator(tmp, ignored))
      if (e.path().filename().string().starts_with("rig_identify_fit_table_runs_") && e.path() != d)
        std::filesystem::remove_all(e.path(), ignored);
    std::filesystem::create_directories(d);
    const int lock = ::open((d / "lock").c_str(), O_CREAT | O_RDWR, 0644);
    ::flock(lock, LOCK_EX);
    if (!std::filesystem::exists(d / "complete")) {
      for (int seed = 1; seed <= 3; ++seed) {
        const auto run = d / fmt::format("run{}", seed);
        const RunResult r =
            run_rig(fmt::format("commission --emulate --seed {} --quiet --force --test {} --out {}",
                                seed, RIG_IDENTIFY_PROFILE, run.string()),
                    d);
        EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
      }
      std::ofstream(d / "complete") << "1\n";
    }
    ::flock(lock, LOCK_UN);
    ::close(lock);
    return d;
  }();
  return dir;
}

std::string recording(int seed) {
  return (runs_dir() / fmt::format("run{}", seed) / "recording.csv").string();
}

// Runs rig identify with its output in `name`/out (returned in out_dir when asked).
json identify(const std::string& args, const std::string& name, RunResult& r,
              std::filesystem::path* out_dir = nullptr) {
  const auto work = scratch(name);
  if (out_dir) *out_dir = work / "out";
  r = run_rig("identify " + args + " --json --out " + (work / "out").string(), work);
  if (r.exit_code != 0) return nullptr;
  return json::parse(r.out);
}

std::map<std::string, json> rows_by_name(const json& rep) {
  std::map<std::string, json> out;
  for (const json& row : rep["fit_table"]["rows"]) out[row["name"].get<std::string>()] = row;
  return out;
}

TEST(IdentifyFitTable, ChosenOnBIsWithinOnePointOfTheBestOnC) {
  RunResult rb, rc;
  const json on_b =
      identify("--recording " + recording(1) + " --validation " + recording(2), "choose_b", rb);
  ASSERT_EQ(rb.exit_code, 0) << rb.err;
  const json on_c =
      identify("--recording " + recording(1) + " --validation " + recording(3), "score_c", rc);
  ASSERT_EQ(rc.exit_code, 0) << rc.err;
  const std::string chosen = on_b["structure"]["name"];
  const auto c_rows = rows_by_name(on_c);
  ASSERT_TRUE(c_rows.count(chosen)) << chosen;
  double best_c = -1e9;
  std::string best_name;
  for (const auto& [name, row] : c_rows) {
    if (row["ok"].get<bool>() && row["validation_fit_pct"].get<double>() > best_c)
      best_c = row["validation_fit_pct"], best_name = name;
  }
  const double chosen_c = c_rows.at(chosen)["validation_fit_pct"];
  fmt::print(
      "emulated seeds 1 (estimation), 2 (choice), 3 (check), {} structures: chosen on 2: {} "
      "({:.2f} %); on 3 it scores {:.2f} %, the best on 3 is {} ({:.2f} %): {:.2f} points "
      "behind\n",
      on_b["fit_table"]["rows"].size(), chosen, on_b["validation_fit_pct"].get<double>(), chosen_c,
      best_name, best_c, best_c - chosen_c);
  EXPECT_GE(chosen_c, best_c - kChoiceMarginPct);
  // The validation record takes no part in the estimate: every structure's estimation fit
  // is the same whichever record validates.
  for (const auto& [name, row] : rows_by_name(on_b)) {
    if (!row["ok"].get<bool>() || !c_rows.at(name)["ok"].get<bool>()) continue;
    EXPECT_DOUBLE_EQ(row["estimation_fit_pct"].get<double>(),
                     c_rows.at(name)["estimation_fit_pct"].get<double>())
        << name;
  }
  // The table covers orders 1..6 with every numerator order below, with and without a dead
  // time, for the three estimators.
  EXPECT_EQ(on_b["fit_table"]["rows"].size(), 21u * 2u * 3u);
  EXPECT_EQ(on_b["validation"]["data"], "validation record");
  EXPECT_TRUE(on_b["validation"]["residual_tests"].contains("independent"));
  EXPECT_GT(on_b["bode_band"]["factor"].get<double>(), 1.96);
}

TEST(IdentifyFitTable, DeadTimeRefersToThePlantAsCommissionsModel) {
  const json commission = json::parse(slurp(runs_dir() / "run1" / "model.json"));
  RunResult r;
  std::filesystem::path out;
  const json rep =
      identify("--recording " + recording(1) + " --order 2/0 --method mmfm+oe --delay estimated",
               "timing", r, &out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double commission_s = commission["delay_s"];
  const double identify_s = rep["delay"]["value_s"];
  const double after_s = rep["records"][0]["y_sampled_after_s"];
  fmt::print(
      "dead time: rig commission {:.4f} s, rig identify {:.4f} s (y sampled {:.3f} s "
      "after u, correction {:+.4f} s)\n",
      commission_s, identify_s, after_s, rep["timing"]["correction_s"].get<double>());
  EXPECT_EQ(rep["timing"]["refers_to"], "plant");
  // --delay estimated: only the structure with a dead time.
  ASSERT_EQ(rep["fit_table"]["rows"].size(), 1u);
  EXPECT_TRUE(rep["fit_table"]["rows"][0]["delay_estimated"].get<bool>());
  EXPECT_NEAR(rep["timing"]["correction_s"].get<double>(), after_s - 0.005, 1e-12);
  EXPECT_NEAR(identify_s, commission_s, kDelayAgreementS);
  const json model = json::parse(slurp(out / "model.json"));
  EXPECT_EQ(model["timing"], "plant");
}

TEST(IdentifyFitTable, SeveralEstimationRecords) {
  RunResult r;
  const json rep = identify("--recording " + recording(1) + " --estimation " + recording(3) +
                                " --validation " + recording(2) + " --order 2/0",
                            "several", r);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(rep["records"].size(), 3u);
  EXPECT_EQ(rep["records"][1]["role"], "estimation");
  EXPECT_EQ(rep["records"][2]["role"], "validation");
  const double fn_hz = rep["derived"]["fn_hz"];
  fmt::print("estimated on seeds 1 and 3, validated on 2: {} fn {:.4f} Hz, fit {:.2f} %\n",
             rep["structure"]["name"].get<std::string>(), fn_hz,
             rep["validation_fit_pct"].get<double>());
  EXPECT_NEAR(fn_hz, 2.03, 0.03 * 2.03);
}

TEST(IdentifyFitTable, RecordsThatDoNotGoTogetherAreOneLineErrors) {
  RunResult r;
  identify("--recording " + recording(1) + " --estimation " + recording(2), "no_validation", r);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--validation"), std::string::npos) << r.err;
  // An estimation record sampled otherwise (y read before the write, as in real time).
  const auto work = scratch("timed_otherwise");
  std::filesystem::copy_file(recording(2), work / "other.csv");
  json sidecar = json::parse(slurp(runs_dir() / "run2" / "recording.json"));
  sidecar["y_sampled_after_s"] = 0.0;
  std::ofstream(work / "other.json") << sidecar.dump(2);
  identify("--recording " + recording(1) + " --estimation " + (work / "other.csv").string() +
               " --validation " + recording(3),
           "timing_error", r);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("y_sampled_after_s"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  identify("--recording " + recording(1) + " --method mmfm,arx", "bad_method", r);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--method"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace rig::testing
