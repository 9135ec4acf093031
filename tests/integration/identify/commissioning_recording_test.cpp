// rig identify on the recording a commissioning test leaves: by default only the excitation
// phase (the longest contiguous run of phase = 2 rows) is identified, which recovers the
// Stornoway electromechanical mode (2.03 Hz, plantsim/presets/stornoway.tf.json); and a
// recording cut mid-line, as a killed rig leaves it, is still accepted.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace rig::testing {
namespace {

constexpr double kModeHz = 2.03;  // the preset's electromechanical mode

// One lockstep commissioning run shared by the tests of this file (seed 3).
const std::filesystem::path& commissioning_dir() {
  static const std::filesystem::path dir = [] {
    const auto d = scratch("commissioning");
    const RunResult r =
        run_rig(fmt::format("commission --emulate --seed 3 --quiet --test {} --out {}",
                            RIG_IDENTIFY_PROFILE, (d / "run").string()),
                d);
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    return d / "run";
  }();
  return dir;
}

nlohmann::json identify(const std::filesystem::path& recording, const std::string& extra,
                        const std::filesystem::path& out, RunResult& r) {
  r = run_rig(fmt::format("identify --recording {} --order 2/0 {} --out {}", recording.string(),
                          extra, out.string()),
              out.parent_path());
  if (r.exit_code != 0) return nullptr;
  return nlohmann::json::parse(slurp(out / "report.json"));
}

TEST(IdentifyCommissioning, ExcitationRowsGiveTheModeWithin3Percent) {
  const auto rec = commissioning_dir() / "recording.csv";
  ASSERT_TRUE(std::filesystem::exists(rec));
  const auto work = scratch("excitation");
  RunResult r;
  const auto rep = identify(rec, "", work / "out", r);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const auto& rows = rep["recording"]["rows_used"];
  EXPECT_EQ(rows["selection"], "excitation");
  EXPECT_EQ(rows["phase_code"], 2);
  EXPECT_LT(rows["count"].get<long>(), rows["of"].get<long>());
  EXPECT_EQ(rep["recording"]["rows"], rows["count"]);
  EXPECT_NE(r.out.find("excitation phase only"), std::string::npos) << r.out;
  const double fn_hz = rep["derived"]["fn_hz"];
  fmt::print("excitation rows {}+{} of {}: fn {:.4f} Hz ({:+.2f} % against {} Hz), zeta {:.3f}\n",
             rows["first_row"].get<long>(), rows["count"].get<long>(), rows["of"].get<long>(),
             fn_hz, 100.0 * (fn_hz / kModeHz - 1.0), kModeHz, rep["derived"]["zeta"].get<double>());
  EXPECT_EQ(rep["model"]["order"]["n"], 2);
  EXPECT_NEAR(fn_hz, kModeHz, 0.03 * kModeHz);
  // --rows all mixes in the steady state, the pilot and the swept sine (one frequency at a
  // time, long stretches of it): a worse estimate of the mode.
  RunResult all;
  const auto whole = identify(rec, "--rows all", work / "all", all);
  ASSERT_EQ(all.exit_code, 0) << all.out << all.err;
  EXPECT_EQ(whole["recording"]["rows_used"]["selection"], "all");
  EXPECT_EQ(whole["recording"]["rows"], rows["of"]);
  const double fn_all_hz = whole["derived"]["fn_hz"];
  fmt::print("--rows all: fn {:.4f} Hz ({:+.2f} %)\n", fn_all_hz,
             100.0 * (fn_all_hz / kModeHz - 1.0));
  EXPECT_GT(std::abs(fn_all_hz - kModeHz), std::abs(fn_hz - kModeHz));
}

// A killed rig: the last row cut mid-line, the sidecar never completed.
TEST(IdentifyCommissioning, RecordingCutMidLineIsAccepted) {
  const auto src = commissioning_dir() / "recording.csv";
  ASSERT_TRUE(std::filesystem::exists(src));
  const auto work = scratch("cut");
  const std::string text = slurp(src);
  // Cut inside the excitation (3/8 of the file; the swept sine follows it), a few characters
  // into a row.
  const std::size_t line_start = text.find('\n', text.size() * 3 / 8) + 1;
  ASSERT_LT(line_start + 5, text.size());
  std::ofstream(work / "killed.csv", std::ios::binary) << text.substr(0, line_start + 5);
  auto sidecar = nlohmann::json::parse(slurp(commissioning_dir() / "recording.json"));
  sidecar.erase("rows");
  sidecar.erase("complete");
  std::ofstream(work / "killed.json") << sidecar.dump(2);
  RunResult r;
  const auto rep = identify(work / "killed.csv", "", work / "out", r);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  ASSERT_FALSE(rep["recording"]["warnings"].empty()) << "the partial last line must be reported";
  EXPECT_EQ(rep["recording"]["rows_used"]["selection"], "excitation");
  const double fn_hz = rep["derived"]["fn_hz"];
  fmt::print("cut recording: {} warning(s), first: {}; fn {:.4f} Hz from {} excitation rows\n",
             rep["recording"]["warnings"].size(),
             rep["recording"]["warnings"][0].get<std::string>(), fn_hz,
             rep["recording"]["rows_used"]["count"].get<long>());
  // Every complete row is kept (header and the partial row are not data).
  const auto complete_lines =
      std::count(text.begin(), text.begin() + static_cast<long>(line_start), '\n');
  EXPECT_EQ(rep["recording"]["rows_used"]["of"].get<long>(), complete_lines - 1);
  EXPECT_TRUE(std::isfinite(fn_hz) && fn_hz > 0.0);
  EXPECT_TRUE(std::filesystem::exists(work / "out/model.json"));
}

}  // namespace
}  // namespace rig::testing
