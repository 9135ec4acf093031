// The session's compare phase and `rig compare` on the files the session wrote judge the same
// swept-sine points. Before the FRF file kept the estimator's `valid` verdict, a noisy run
// (meas.noise_kw=15 from t=0) was judged on 7 points by the session and on 12 by `rig compare` on
// its sweep.csv (worst phase error 3.3 against 7.4 deg).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

#include "tests/integration/commission/run_rig.hpp"

namespace rig::testing {
namespace {

// model.json, or (a run that exits 1 writes none) the same model from report.json's "mmfm".
std::filesystem::path model_of(const std::filesystem::path& out, const nlohmann::json& report) {
  if (std::filesystem::exists(out / "model.json")) return out / "model.json";
  const nlohmann::json& m = report.at("mmfm");
  const auto path = std::filesystem::path(out.string() + ".model.json");
  std::ofstream(path) << nlohmann::json{
      {"type", "tf"},
      {"num", m.at("num")},
      {"den", m.at("den")},
      {"delay_s",
       m.at("delay_s")}}.dump();
  return path;
}

TEST(Commission, RigCompareOnTheSessionsSweepJudgesTheSamePoints) {
  const auto out = fresh_dir("compare-agrees");
  const std::string profile = (source_dir() / "tests/integration/commission/short.toml").string();
  const int code = run_rig(fmt::format("commission --emulate --seed 1 --fault meas.noise_kw=15@t=0 "
                                       "--test {} --quiet --out {}",
                                       profile, out.string()),
                           log_beside(out));
  ASSERT_TRUE(code == 0 || code == 1) << read_text(log_beside(out));
  const nlohmann::json report = read_json(out / "report.json");
  ASSERT_FALSE(report.at("mmfm").is_null()) << read_text(log_beside(out));
  const nlohmann::json& session = report.at("compare").at("sweep");
  ASSERT_FALSE(session.is_null());

  // The test file's [compare] defaults are rig compare's defaults.
  const auto cmp = std::filesystem::path(out.string() + ".compare");
  const int cmp_code =
      run_rig(fmt::format("compare --model {} --frf {} --out {}", model_of(out, report).string(),
                          (out / "sweep.csv").string(), cmp.string()),
              log_beside(cmp));
  ASSERT_TRUE(cmp_code == 0 || cmp_code == 1) << read_text(log_beside(cmp));
  const nlohmann::json cli = read_json(cmp / "report.json");
  fmt::print("session: {}\nrig compare: {}\n", session.at("summary").get<std::string>(),
             cli.at("summary").get<std::string>());
  EXPECT_EQ(cli.at("checked"), session.at("checked"));
  EXPECT_EQ(cli.at("failed"), session.at("failed"));
  EXPECT_EQ(cli.at("verdict"), session.at("verdict"));
  const auto& a = session.at("rows");
  const auto& b = cli.at("rows");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].at("checked"), b[i].at("checked")) << "row " << i;
    EXPECT_EQ(a[i].at("pass"), b[i].at("pass")) << "row " << i;
  }
  EXPECT_EQ(cmp_code, session.at("verdict") == "pass" ? 0 : 1);
}

}  // namespace
}  // namespace rig::testing
