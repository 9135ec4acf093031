#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "concealed.hpp"
#include "rig/diagnose/report_out.hpp"
#include "rig/model/model_file.hpp"

namespace rig::diagnose {
namespace {

TEST(Report, JsonHasTheDocumentedKeysAndTheModelRoundTrips) {
  ConcealedSpec spec;
  spec.effect = Effect::kDeadTime;
  spec.seed = 41;
  spec.duration_s = 120.0;
  const ConcealedRecording rec = make_concealed(spec);
  const DiagnoseResult r = diagnose(rec.input);
  const nlohmann::json j = report_json(r, {"rec.csv", "model.json", "u", "y"});
  for (const char* key : {"verdict", "hypotheses", "location", "explanation"})
    EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key : {"band_hz", "time_windows", "amplitude_dependent"})
    EXPECT_TRUE(j["location"].contains(key)) << key;
  ASSERT_FALSE(j["hypotheses"].empty());
  for (const char* key : {"effect", "params", "fit_before", "fit_after", "validation_fit_before",
                          "validation_fit_after", "score"})
    EXPECT_TRUE(j["hypotheses"][0].contains(key)) << key;
  EXPECT_EQ(j["verdict"], "dead_time");

  model::ModelFile base;
  base.tf = rec.input.model;
  const model::ModelFile aug = augmented_model(r, base);
  const auto dir = std::filesystem::temp_directory_path() / "rig_diagnose_report_test";
  std::filesystem::create_directories(dir);
  model::write_model(dir / "augmented.json", aug);
  const model::ModelFile back = model::read_model(dir / "augmented.json");
  EXPECT_NEAR(back.tf.delay_s, 0.10, 0.02);  // 60 ms nominal + 40 ms found
  EXPECT_EQ(back.extra["augmentation"][0]["effect"], "dead_time");

  write_report_html(r, {"rec.csv", "model.json", "u", "y"}, dir / "report.html");
  std::ifstream in(dir / "report.html");
  const std::string html((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(html.find("dead_time"), std::string::npos);
  EXPECT_NE(html.find("Residual spectrum"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// A sensor lag whose corner is too near half the sample rate has no noise roll-off figure:
// the explanation says why instead of printing "nan".
TEST(Report, SensorLagWithoutRolloffFigureIsExplainedInWords) {
  DiagnoseResult r;
  r.verdict = "sensor_lag";
  HypothesisFit h;
  h.effects = {AppliedEffect{Effect::kSensorLag, {0.004}}};
  h.validation_fit_before = 60.0;
  h.validation_fit_after = 70.0;
  r.hypotheses = {h};
  r.chosen_index = 0;
  r.problem.dt_s = 0.01;
  const std::string text = explain(r);
  EXPECT_EQ(text.find("nan"), std::string::npos) << text;
  EXPECT_NE(text.find("too near half the sample rate"), std::string::npos) << text;
}

}  // namespace
}  // namespace rig::diagnose
