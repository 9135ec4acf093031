// The stornoway preset: TOML file = compiled preset, linearised figures in their specified
// ranges, the SOPDT approximation the identification relies on, and the committed model file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/linearise.hpp"

namespace plantsim {
namespace {

std::filesystem::path source_dir() {
  const char* dir = std::getenv("RIG_SOURCE_DIR");
  return dir != nullptr ? dir : PLANT_SOURCE_DIR;
}

const LinearModel& stornoway() {
  static const LinearModel lm = linearise(PlantOptions{});
  return lm;
}

double db(std::complex<double> ratio) { return 20.0 * std::log10(std::abs(ratio)); }
double deg(std::complex<double> ratio) { return std::arg(ratio) * 180.0 / std::numbers::pi; }

TEST(PlantPreset, TomlFileEqualsCompiledPreset) {
  if (source_dir().empty()) GTEST_SKIP() << "RIG_SOURCE_DIR not set";
  const Params from_file = load_toml(source_dir() / "plantsim/presets/stornoway.toml");
  const Params compiled = preset("stornoway");
  for (std::size_t i = 0; i < kParamCount; ++i) {
    EXPECT_EQ(from_file[static_cast<P>(i)], compiled[static_cast<P>(i)]) << param_specs()[i].name;
  }
}

TEST(PlantPreset, LinearisedModeDampingAndDelayInSpec) {
  const LinearModel& lm = stornoway();
  std::cout << "fn " << lm.fn_hz << " Hz, zeta " << lm.zeta << ", delay " << lm.delay_s << " s, dc "
            << lm.dc_gain_kw_per_pct << " kW/%\n";
  EXPECT_GE(lm.fn_hz, 1.8);
  EXPECT_LE(lm.fn_hz, 2.2);
  EXPECT_GE(lm.zeta, 0.07);
  EXPECT_LE(lm.zeta, 0.15);
  EXPECT_GE(lm.delay_s, 0.040);
  EXPECT_LE(lm.delay_s, 0.080);
  // 1 % bias -> 1 % of 4.6 MW at steady state (the bias is scaled by R in the governor).
  EXPECT_NEAR(lm.dc_gain_kw_per_pct, 46.0, 0.01);
}

TEST(PlantPreset, SecondOrderPlusDeadTimeMatchesOverIdentificationBand) {
  const LinearModel& lm = stornoway();
  const SopdtFit& s = lm.sopdt;
  std::cout << "SOPDT K " << s.gain_kw_per_pct << " kW/%, fn " << s.fn_hz << " Hz, zeta " << s.zeta
            << ", Td " << s.delay_s << " s\n";
  double worst_db = 0.0, worst_deg = 0.0;
  for (int i = 0; i <= 900; ++i) {  // independent, finer grid than the fit used
    const double f = 0.5 + 4.5 * i / 900.0;
    const std::complex<double> r = s.response(f) / lm.response(f);
    worst_db = std::max(worst_db, std::abs(db(r)));
    worst_deg = std::max(worst_deg, std::abs(deg(r)));
  }
  std::cout << "SOPDT worst error 0.5-5 Hz: " << worst_db << " dB, " << worst_deg << " deg\n";
  EXPECT_LE(worst_db, 0.5);
  EXPECT_LE(worst_deg, 3.0);
  EXPECT_GE(s.delay_s, 0.040);
  EXPECT_LE(s.delay_s, 0.080);
  EXPECT_NEAR(s.fn_hz, lm.fn_hz, 0.1);
}

TEST(PlantPreset, RationalTfWithDelayMatchesExactLinearResponse) {
  const LinearModel& lm = stornoway();
  for (int i = 0; i <= 400; ++i) {
    const double f = 0.002 * std::pow(10000.0, i / 400.0);  // 0.002-20 Hz
    const std::complex<double> r = lm.tf.response(f) / lm.response(f);
    ASSERT_LT(std::abs(db(r)), 0.02) << f;
    ASSERT_LT(std::abs(deg(r)), 0.15) << f;
  }
}

TEST(PlantPreset, IslandedPresetLinearisesToAStableModel) {
  PlantOptions o;
  o.preset = "stornoway_island";
  const LinearModel lm = linearise(o);
  std::cout << "island: dc " << lm.dc_gain_kw_per_pct << " kW/%, fn " << lm.fn_hz << " Hz, zeta "
            << lm.zeta << ", tf error " << lm.tf_max_error_db << " dB\n";
  // Islanded, the load takes P_L0 (1 + D_L dw): the bias moves the speed, and with it the
  // power, only through the load's frequency dependence, so the gain is far below 46 kW/%.
  EXPECT_TRUE(std::isfinite(lm.dc_gain_kw_per_pct));
  EXPECT_GT(lm.dc_gain_kw_per_pct, 0.0);
  EXPECT_LT(lm.dc_gain_kw_per_pct, 46.0);
  EXPECT_LT(lm.tf_max_error_db, 0.1);
}

TEST(PlantPreset, CommittedModelFileMatchesFreshLinearisation) {
  if (source_dir().empty()) GTEST_SKIP() << "RIG_SOURCE_DIR not set";
  std::ifstream in(source_dir() / "plantsim/presets/stornoway.tf.json");
  ASSERT_TRUE(in) << "plantsim/presets/stornoway.tf.json missing";
  const auto j = nlohmann::json::parse(in);
  const LinearModel& lm = stornoway();
  EXPECT_EQ(j.at("type"), "tf");
  EXPECT_EQ(j.at("input"), "bias_pct");
  EXPECT_EQ(j.at("output"), "power_kw");
  const auto num = j.at("num").get<std::vector<double>>();
  const auto den = j.at("den").get<std::vector<double>>();
  ASSERT_EQ(num.size(), static_cast<std::size_t>(lm.tf.num.size()));
  ASSERT_EQ(den.size(), static_cast<std::size_t>(lm.tf.den.size()));
  for (std::size_t k = 0; k < num.size(); ++k)
    EXPECT_NEAR(num[k], lm.tf.num[k], 1e-6 * std::abs(lm.tf.num[k]));
  for (std::size_t k = 0; k < den.size(); ++k)
    EXPECT_NEAR(den[k], lm.tf.den[k], 1e-6 * std::abs(lm.tf.den[k]));
  EXPECT_NEAR(j.at("delay_s").get<double>(), lm.delay_s, 1e-12);
  const auto& d = j.at("derived");
  EXPECT_NEAR(d.at("fn_hz").get<double>(), lm.fn_hz, 1e-6);
  EXPECT_NEAR(d.at("zeta").get<double>(), lm.zeta, 1e-6);
  EXPECT_NEAR(d.at("dc_gain_kw_per_pct").get<double>(), lm.dc_gain_kw_per_pct, 1e-6);
}

TEST(PlantPreset, WriteTfJsonRoundTrips) {
  const auto file = std::filesystem::temp_directory_path() / "plant_preset_tf_test.json";
  write_tf_json(stornoway(), file);
  std::ifstream in(file);
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("num").size(), static_cast<std::size_t>(stornoway().tf.num.size()));
  EXPECT_EQ(j.at("units").at("output"), "kW");
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace plantsim
