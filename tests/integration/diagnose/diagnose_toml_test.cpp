// `rig diagnose --model PLANT.toml` as a process (build/bin/rig, which runs the plantsim
// beside it): a recording of the emulated plant (plantsim in-process, CVODE) with one
// parameter changed, diagnosed against the unchanged preset TOML. Checks the verdict, the
// augmented plant TOML (the right key, within 20 % of the truth) and the plant check.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <toml++/toml.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "plant_cases.hpp"
#include "plantsim/plant/config.hpp"
#include "plantsim/plant/parameters.hpp"
#include "plantsim/plant/plant.hpp"
#include "recording_out.hpp"
#include "rig/cli/diagnose_plant.hpp"
#include "rig/signal/excitation.hpp"

namespace fs = std::filesystem;

namespace {

fs::path bin_dir() {
  const char* b = std::getenv("RIG_BIN_DIR");
  return b ? b : "build/bin";
}
fs::path source_dir() {
  const char* s = std::getenv("RIG_SOURCE_DIR");
  return s ? s : ".";
}

// The plant cases' recording (plant_cases.hpp: 10 ms ticks, +-3 sigma Gaussian bias of
// 0.8 %, 4 Hz, the preset's own disturbances, 5 s settling): rec.csv (t,u,y) and its sidecar.
void write_plant_recording(const fs::path& dir, const std::vector<std::string>& faults,
                           std::uint64_t seed, double duration_s) {
  const auto rec = rig::diagnose::bench::record_plant(faults, seed, seed, duration_s, 5.0);
  rig::diagnose::bench::write_diagnose_recording(dir, rec.u, rec.y, 0.01, seed, std::nullopt,
                                                 nullptr);
  std::printf("recording: faults [%s] seed %llu, %.0f s\n",
              faults.empty() ? "" : faults.front().c_str(), static_cast<unsigned long long>(seed),
              duration_s);
}

struct RigRun {
  int code = -1;
  std::string output;
};

RigRun run_bin(const std::string& program, const std::string& args) {
  const std::string cmd = (bin_dir() / program).string() + " " + args + " 2>&1";
  RigRun r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) r.output += buf;
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::printf("$ %s %s\n%s", program.c_str(), args.c_str(), r.output.c_str());
  return r;
}

RigRun run_rig(const std::string& args) { return run_bin("rig", "diagnose " + args); }

class DiagnoseToml : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(bin_dir() / "rig") || !fs::exists(bin_dir() / "plantsim"))
      GTEST_SKIP() << "rig/plantsim executables not built in " << bin_dir();
    dir_ = fs::temp_directory_path() / ("rig_diagnose_toml_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string args(const fs::path& model) const {
    return "--recording " + (dir_ / "rec.csv").string() + " --model " + model.string() + " --out " +
           (dir_ / "out").string();
  }
  nlohmann::json report() const {
    std::ifstream in(dir_ / "out" / "report.json");
    return nlohmann::json::parse(in);
  }

  fs::path dir_;
};

// Fuel dead time 58.3 ms (the preset's 30/N + 60/(n N)) raised to 90 ms.
TEST_F(DiagnoseToml, LongerFuelDeadTimeGoesBackIntoThePlant) {
  write_plant_recording(dir_, {"engine.dead_time_s=0.09@t=0"}, 11, 150.0);
  const RigRun r = run_rig(args(source_dir() / "plantsim/presets/stornoway.toml"));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = report();
  ASSERT_EQ(j["verdict"], "dead_time");
  const toml::table aug = toml::parse_file((dir_ / "out" / "augmented_plant.toml").string());
  const auto td = aug["engine"]["dead_time_s"].value<double>();
  ASSERT_TRUE(td.has_value());
  EXPECT_NEAR(*td, 0.09, 0.09 * 0.2);
  EXPECT_EQ(j["plant_model"]["changes"][0]["key"], "engine.dead_time_s");
  // Untouched keys keep their values.
  EXPECT_EQ(aug["alt"]["d_pu"].value<double>(), 11.0);
  const double before = j["plant_check"]["fit_before_pct"];
  const double after = j["plant_check"]["fit_after_pct"];
  EXPECT_GT(after, before + 5.0);
  // report.html shows what went back into the plant and the replays.
  std::ifstream page(dir_ / "out" / "report.html");
  const std::string html((std::istreambuf_iterator<char>(page)), std::istreambuf_iterator<char>());
  EXPECT_NE(html.find("<h2>Plant</h2>"), std::string::npos);
  EXPECT_NE(html.find("engine.dead_time_s"), std::string::npos);
  EXPECT_NE(html.find(fmt::format("fit {:.1f} % -&gt; {:.1f} %", before, after)),
            std::string::npos);
  EXPECT_NE(html.find("the plant replayed, as given and augmented"), std::string::npos);
}

// Transducer gain error 0.9 on a plant file that starts from the preset and overrides a key.
TEST_F(DiagnoseToml, TransducerGainErrorOnAPresetBasedFile) {
  std::ofstream(dir_ / "plant.toml") << "preset = \"stornoway\"\n[meas]\nnoise_kw = 5\n";
  write_plant_recording(dir_, {"meas.gain=0.9@t=0"}, 12, 150.0);
  const RigRun r = run_rig(args(dir_ / "plant.toml"));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = report();
  ASSERT_EQ(j["verdict"], "gain_change");
  const toml::table aug = toml::parse_file((dir_ / "out" / "augmented_plant.toml").string());
  EXPECT_EQ(aug["preset"].value<std::string>(), "stornoway");
  const auto gain = aug["meas"]["gain"].value<double>();
  ASSERT_TRUE(gain.has_value());
  EXPECT_NEAR(*gain, 0.9, 0.9 * 0.2);
  EXPECT_GT(j["plant_check"]["fit_after_pct"].get<double>(),
            j["plant_check"]["fit_before_pct"].get<double>());
}

TEST_F(DiagnoseToml, PlantTheSimulatorRejectsIsOneLineExit2) {
  write_plant_recording(dir_, {}, 13, 10.0);
  std::ofstream(dir_ / "bad.toml") << "[gov]\nno_such_key = 1\n";
  const RigRun r = run_rig(args(dir_ / "bad.toml"));
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find("bad.toml"), std::string::npos);
  EXPECT_NE(r.output.find("no_such_key"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "report.json"));
}

// plantsim --replay against the plant stepped here with the same disturbances switched off:
// bias u_k applied, y_k read at t_k, one tick on.
TEST_F(DiagnoseToml, ReplayIsThePlantsNoiseFreeResponse) {
  const Eigen::Index n = 1500;
  rig::signal::GaussianOptions go;
  go.n = n, go.dt_s = 0.02, go.bandwidth_hz = 3.0, go.sigma = 1.0, go.seed = 21;
  const Eigen::VectorXd u = rig::signal::gaussian_excitation(go);
  {
    std::ofstream in(dir_ / "in.csv");
    in.precision(17);  // round-trips the doubles: both runs see bit-identical biases
    in << "# bias only\nt,bias\n";
    for (Eigen::Index k = 0; k < n; ++k) in << static_cast<double>(k) * 0.02 << ',' << u(k) << '\n';
  }
  const std::string plant = (source_dir() / "plantsim/presets/stornoway.toml").string();
  const RigRun r = run_bin("plantsim", "--config " + plant + " --replay " +
                                           (dir_ / "in.csv").string() + " --replay-column bias" +
                                           " --replay-out " + (dir_ / "out.csv").string());
  ASSERT_EQ(r.code, 0) << r.output;
  plantsim::PlantOptions po;
  po.config = plant;
  po.tick = std::chrono::milliseconds(20);
  po.faults = {"meas.noise_kw=0@t=0", "meas.drift_kw=0@t=0", "meas.pickup_kw=0@t=0",
               "meas.quant_kw=0@t=0", "engine.ripple=0@t=0"};
  auto p = plantsim::make_plant(po);
  std::ifstream out(dir_ / "out.csv");
  std::string line;
  std::getline(out, line);
  ASSERT_EQ(line, "t,u,power_kw");
  double max_err = 0.0, lo = 1e300, hi = -1e300;
  for (Eigen::Index k = 0; k < n; ++k) {
    ASSERT_TRUE(std::getline(out, line)) << "row " << k;
    const double y = std::stod(line.substr(line.rfind(',') + 1));
    p->set_bias_pct(u(k));
    max_err = std::max(max_err, std::abs(y - p->measure().power_w / 1e3));
    lo = std::min(lo, y), hi = std::max(hi, y);
    p->step();
  }
  std::printf("replay vs in-process: max |diff| %.3g kW, output span %.1f kW\n", max_err, hi - lo);
  EXPECT_LT(max_err, 1e-3);
  EXPECT_GT(hi - lo, 100.0);  // the bias (1 % rms) moves the set by about 46 kW per %

  const RigRun bad =
      run_bin("plantsim", "--config " + plant + " --replay " + (dir_ / "in.csv").string() +
                              " --replay-out " + (dir_ / "o2.csv").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.output.find("no column 'u'"), std::string::npos) << bad.output;
}

// The mapping table on its own: the preset's parameters (as plantsim --list-params gives
// them) and hand-made hypotheses with known parameters.
rig::cli::PlantModel stornoway_model() {
  rig::cli::PlantModel m;
  m.toml = "stornoway.toml";
  const plantsim::Params p = plantsim::preset("stornoway");
  const auto& specs = plantsim::param_specs();
  for (std::size_t i = 0; i < specs.size(); ++i) {
    m.params[std::string(specs[i].name)] = p[static_cast<plantsim::P>(i)];
    m.ranges[std::string(specs[i].name)] = {specs[i].min_value, specs[i].max_value};
  }
  return m;
}

rig::cli::PlantMapping map(std::vector<rig::diagnose::AppliedEffect> effects,
                           std::vector<std::pair<std::string, double>> derived = {}) {
  rig::diagnose::HypothesisFit h;
  h.effects = std::move(effects);
  h.derived = std::move(derived);
  const double w = 2.0 * 3.141592653589793 * 2.0;  // a 2 Hz mode with zeta 0.1
  const rig::model::TransferFunction tf{Eigen::VectorXd::Constant(1, w * w),
                                        Eigen::Vector3d(1.0, 2.0 * 0.1 * w, w * w), 0.06};
  const Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(101, -2.0, 4.0);  // mean 1 %
  return rig::cli::plant_changes(h, stornoway_model(), tf, u);
}

double changed(const rig::cli::PlantMapping& m, const std::string& key) {
  for (const auto& c : m.changes)
    if (c.key == key) return c.new_value;
  ADD_FAILURE() << key << " not changed";
  return NAN;
}

TEST(DiagnosePlantMapping, GovernorEffectsInRackAndErrorUnits) {
  using E = rig::diagnose::Effect;
  // Deadband half width 0.2 % of bias on e = R b: R 0.05 x 0.002 = 1e-4 pu.
  EXPECT_NEAR(changed(map({{E::kDeadband, {0.2}}}), "gov.deadband_pu"), 1e-4, 1e-9);
  // Backlash half width 0.5 %: play width 2 x 0.005 pu of rack (R K T4 = 1).
  EXPECT_NEAR(changed(map({{E::kBacklash, {0.5}}}), "gov.backlash_pu"), 0.01, 1e-9);
  EXPECT_NEAR(changed(map({{E::kRateLimit, {20.0, 0.5}}}), "gov.rate_limit_pu_s"), 0.2, 1e-9);
  // Upper limit 1 % above the mean bias (1 %): rack 3500/4600 + 0.02; the lower limit 10 %
  // lies beyond the recorded excursion (3 %) and stays.
  const auto sat = map({{E::kSaturation, {1.0, 10.0, 0.01}}});
  EXPECT_NEAR(changed(sat, "gov.tmax_pu"), 3500.0 / 4600.0 + 0.02, 1e-6);
  EXPECT_EQ(sat.changes.size(), 1u);
  ASSERT_EQ(sat.notes.size(), 1u);
  EXPECT_NE(sat.notes[0].find("gov.tmin_pu left unchanged"), std::string::npos);
}

TEST(DiagnosePlantMapping, LinearEffectsDisturbancesAndPairs) {
  using E = rig::diagnose::Effect;
  // Fuel dead time 30/600 + 60/(12 x 600) = 58.3 ms plus 30 ms.
  EXPECT_NEAR(changed(map({{E::kDeadTime, {0.03}}}), "engine.dead_time_s"), 0.0883333, 1e-6);
  EXPECT_NEAR(changed(map({{E::kSensorLag, {0.077}}}), "meas.transducer_lag_s"), 0.08, 1e-9);
  EXPECT_NEAR(changed(map({{E::kExtraLag, {0.042}}}), "engine.combustion_lag_s"), 0.05, 1e-9);
  // Damping ratio 0.1 -> 0.05: D 11 -> 5.5.
  EXPECT_NEAR(changed(map({{E::kLoadDamping, {0.05}}}), "alt.d_pu"), 5.5, 1e-4);
  const auto pair = map({{E::kGainChange, {0.9}}, {E::kPeriodicDisturbance, {7.3}}},
                        {{"amplitude", 12.0}, {"phase_deg", 30.0}});
  EXPECT_NEAR(changed(pair, "meas.gain"), 0.9, 1e-9);
  EXPECT_NEAR(changed(pair, "meas.pickup_hz"), 7.3, 1e-9);
  EXPECT_NEAR(changed(pair, "meas.pickup_kw"), 12.0, 1e-9);
  // Out of plantsim's range (ac_rc_s <= 1e4 s): clamped, with a note.
  const auto ac = map({{E::kAcCoupling, {2e4}}});
  EXPECT_EQ(changed(ac, "meas.ac_rc_s"), 1e4);
  EXPECT_EQ(ac.notes.size(), 1u);
  const auto res = map({{E::kResonance, {3.0, 0.1, 2.0, 1.0}}});
  EXPECT_TRUE(res.changes.empty());
  EXPECT_EQ(res.notes.size(), 1u);
}

TEST(DiagnosePlantMapping, AugmentedTomlKeepsThePresetAndLoadsInPlantsim) {
  const fs::path dir = fs::temp_directory_path() / ("rig_plant_map_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "in.toml") << "preset = \"stornoway\"  # base\n[meas]\nnoise_kw = 2\n";
  const auto m = map({{rig::diagnose::Effect::kDeadTime, {0.03}}});
  std::ofstream(dir / "out.toml") << rig::cli::augmented_plant_toml(dir / "in.toml", m, {"x"});
  const plantsim::Params p = plantsim::load_toml(dir / "out.toml");
  EXPECT_NEAR(p[plantsim::P::kEngDeadTime], 0.0883333, 1e-6);
  EXPECT_EQ(p[plantsim::P::kMeasNoise], 2.0);  // kept from the input
  EXPECT_EQ(p[plantsim::P::kAltD], 11.0);      // from the preset
  fs::remove_all(dir);
}

}  // namespace
