// `rig identify` end to end: a recording of a known second-order plant with dead time,
// written by the session recorder, identified by the real executable.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "cli_runner.hpp"
#include "rig/io/recording_writer.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/excitation.hpp"

namespace rig {
namespace {

using testing::run_rig;
using testing::scratch;

constexpr double kDt = 0.01;
constexpr std::uint64_t kSeed = 4242;

// Stornoway-like power loop (MMFM.md section 1): 1 / (0.07 s^2 + 0.19 s + 11.05), Td 0.1 s.
// gain 1/11.05 = 0.0905, fn = sqrt(11.05/0.07)/(2 pi) = 2.00 Hz, zeta = 0.108.
model::TransferFunction plant() {
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, 1.0);
  tf.den = (Eigen::VectorXd(3) << 0.07, 0.19, 11.05).finished();
  tf.delay_s = 0.1;
  return tf;
}

// Recording with t, u (%), y (kW) and 5 % output noise, plus the sidecar.
std::filesystem::path write_plant_recording(const std::filesystem::path& dir, Eigen::Index n) {
  signal::GaussianOptions g;
  g.n = n;
  g.dt_s = kDt;
  g.bandwidth_hz = 4.0;
  g.seed = kSeed;
  const Eigen::VectorXd u = signal::gaussian_excitation(g);
  Eigen::VectorXd y = model::simulate(plant(), u, kDt);
  std::mt19937_64 rng(kSeed + 1);
  std::normal_distribution<double> noise(0.0, 0.05 * std::sqrt(y.squaredNorm() / double(n)));
  io::Sidecar meta;
  meta.sample_rate_hz = 1.0 / kDt;
  meta.units = {{"t", "s"}, {"u", "%"}, {"y", "kW"}};
  meta.seed = kSeed;
  const auto csv = dir / "rec.csv";
  io::RecordingWriter writer(csv, {"t", "u", "y"}, meta);
  for (Eigen::Index i = 0; i < n; ++i)
    writer.append({kDt * double(i), u[i], 3500.0 + y[i] + noise(rng)});
  writer.close();
  return csv;
}

TEST(IdentifyCli, RecoversSecondOrderPlantWithDeadTime) {
  const auto dir = scratch("plant");
  const auto csv = write_plant_recording(dir, 16384);
  const auto r = run_rig("identify --recording " + csv.string() + " --order 2/0 --json --out " +
                             (dir / "out").string(),
                         dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rep = nlohmann::json::parse(r.out);
  std::cout << "seed " << kSeed << ": " << rep["derived"].dump() << " delay " << rep["delay"].dump()
            << " fit " << rep["validation_fit_pct"] << "\n";
  EXPECT_EQ(rep["status"], "ok");
  EXPECT_EQ(rep["recording"]["input"], "u");
  EXPECT_EQ(rep["recording"]["dt_source"], "time column t");
  EXPECT_TRUE(rep["quality"]["passed"].get<bool>());
  EXPECT_TRUE(rep["quality"]["flags"].empty()) << rep["quality"].dump();
  const auto& d = rep["derived"];
  EXPECT_NEAR(d["gain"].get<double>(), 1.0 / 11.05, 0.05 / 11.05);
  EXPECT_NEAR(d["fn_hz"].get<double>(), std::sqrt(11.05 / 0.07) / (2 * M_PI), 0.04);
  EXPECT_NEAR(d["zeta"].get<double>(), 0.19 / (2 * std::sqrt(11.05 * 0.07)), 0.03);
  EXPECT_NEAR(rep["delay"]["value_s"].get<double>(), 0.1, 0.02);
  EXPECT_GT(rep["validation_fit_pct"].get<double>(), 85.0);

  const auto model = nlohmann::json::parse(testing::slurp(dir / "out" / "model.json"));
  EXPECT_EQ(model["type"], "tf");
  EXPECT_EQ(model["den"].size(), 3u);
  EXPECT_EQ(model["units"]["output"], "kW");
  const std::string html = testing::slurp(dir / "out" / "report.html");
  EXPECT_NE(html.find("data-charts-expected=\"8\""), std::string::npos);
  EXPECT_EQ(nlohmann::json::parse(testing::slurp(dir / "out" / "report.json")), rep);
}

TEST(IdentifyCli, HumanSummaryWithoutJson) {
  const auto dir = scratch("summary");
  const auto csv = write_plant_recording(dir, 4096);
  const auto r = run_rig("identify --recording " + csv.string() +
                             " --order 2/0 --delay 0.1 --out " + (dir / "out").string(),
                         dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("dead time 0.1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("validation fit"), std::string::npos) << r.out;
}

TEST(IdentifyCli, SwappedChannelsFailTheDataQualityChecks) {
  const auto dir = scratch("swapped");
  const auto csv = write_plant_recording(dir, 8192);
  const auto r = run_rig("identify --recording " + csv.string() +
                             " --input y --output u --order 2/0 --out " + (dir / "out").string(),
                         dir);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("swapped"), std::string::npos) << r.err;
  const auto rep = nlohmann::json::parse(testing::slurp(dir / "out" / "report.json"));
  EXPECT_EQ(rep["status"], "data_quality_failed");
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "model.json"));
}

// Raw and AC-coupled channels side by side, the output's network twice as fast as the
// input's: the coupled pair is not matched, the run stops with exit 1.
TEST(IdentifyCli, MismatchedCouplingNetworksFailTheDataQualityChecks) {
  const auto dir = scratch("coupling");
  signal::GaussianOptions g;
  g.n = 8192;
  g.dt_s = kDt;
  g.bandwidth_hz = 4.0;
  g.seed = kSeed;
  const Eigen::VectorXd u = signal::gaussian_excitation(g);
  const Eigen::VectorXd y = model::simulate(plant(), u, kDt);
  const Eigen::VectorXd u_ac = signal::ac_couple(u, kDt, 1.59);
  const Eigen::VectorXd y_ac = signal::ac_couple(y, kDt, 0.8);
  io::Sidecar meta;
  meta.coupling_rc_s = 1.59;
  meta.coupled_columns = {"u_ac", "y_ac"};
  io::RecordingWriter writer(dir / "rec.csv", {"t", "u", "y", "u_ac", "y_ac"}, meta);
  for (Eigen::Index i = 0; i < g.n; ++i)
    writer.append({kDt * double(i), u[i], y[i], u_ac[i], y_ac[i]});
  writer.close();
  const auto r =
      run_rig("identify --recording " + (dir / "rec.csv").string() +
                  " --input u_ac --output y_ac --order 2/0 --json --out " + (dir / "out").string(),
              dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const auto rep = nlohmann::json::parse(r.out);
  ASSERT_FALSE(rep["quality"]["flags"].empty());
  EXPECT_EQ(rep["quality"]["flags"][0]["name"], "coupling_mismatch");
  EXPECT_NEAR(rep["quality"]["figures"]["coupling_rc_y_ac_s"].get<double>(), 0.8, 0.01);
  EXPECT_NEAR(rep["quality"]["figures"]["coupling_rc_u_ac_s"].get<double>(), 1.59, 0.02);
}

TEST(IdentifyCli, DryerValidationFitOnSecondHalf) {
  const char* shared = std::getenv("RIG_SHARED_DIR");
  const std::filesystem::path dryer =
      std::filesystem::path(shared ? shared : "") / "data" / "daisy" / "dryer.dat";
  if (!shared || !std::filesystem::exists(dryer))
    GTEST_SKIP() << "RIG_SHARED_DIR has no daisy/dryer.dat";
  const auto dir = scratch("dryer");
  const auto r = run_rig("identify --recording " + dryer.string() +
                             " --columns 1,2 --dt 0.08 --json --out " + (dir / "out").string(),
                         dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rep = nlohmann::json::parse(r.out);
  const double fit = rep["validation_fit_pct"].get<double>();
  const double delay = rep["delay"]["value_s"].get<double>();
  std::cout << "dryer: order " << rep["model"]["order"].dump() << ", validation fit " << fit
            << " %, delay " << delay << " s\n";
  EXPECT_EQ(rep["settings"]["estimation_fraction"], 0.5);
  EXPECT_GT(fit, 80.0);  // Ljung's book: a low-order model with a few samples of delay fits ~88 %
  EXPECT_GE(delay, 0.08);
  EXPECT_LE(delay, 0.4);
}

}  // namespace
}  // namespace rig

namespace rig {
namespace {

// Cascaded tanks (nonlinearbenchmark.org): the lower tank's level sensor clips at exactly
// 10.0 (overflow), and the slow, strongly coloured input must not look acausal.
TEST(IdentifyCli, CascadedTanksClippedOutputIsFlaggedButCausalityHolds) {
  const char* shared = std::getenv("RIG_SHARED_DIR");
  const std::filesystem::path csv = std::filesystem::path(shared ? shared : "") / "data" /
                                    "nonlinear_benchmarks" / "cascaded_tanks" / "dataBenchmark.csv";
  if (!shared || !std::filesystem::exists(csv))
    GTEST_SKIP() << "RIG_SHARED_DIR has no cascaded_tanks";
  const auto dir = scratch("tanks");
  const auto r =
      run_rig("identify --recording " + csv.string() +
                  " --input uEst --output yEst --order 2/0 --json --out " + (dir / "out").string(),
              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rep = nlohmann::json::parse(r.out);
  EXPECT_EQ(rep["recording"]["dt_s"], 4.0);
  EXPECT_EQ(rep["recording"]["dt_source"], "scalar column Ts");
  bool clipped = false;
  for (const auto& f : rep["quality"]["flags"]) {
    if (f["name"] == "output_clipped") clipped = true;
    EXPECT_NE(f["severity"], "fatal") << f.dump();
  }
  EXPECT_TRUE(clipped) << rep["quality"].dump();
  EXPECT_GT(rep["quality"]["figures"]["peak_lag_s"].get<double>(), 0.0);
}

}  // namespace
}  // namespace rig
