// Real measured records (RIG_SHARED_DIR/data, README there): the linear TF that identify()
// fits is the model; the diagnosis must run, and on the benchmarks built around a known
// nonlinearity it must not call the linear model sufficient. Verdicts and fits are printed.
// Where a record has a validation part the model did not see, the diagnosis runs on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "rig/diagnose/diagnose.hpp"
#include "rig/ident/identify.hpp"
#include "rig/io/recording.hpp"

namespace fs = std::filesystem;
namespace dg = rig::diagnose;

namespace {

struct RealCase {
  const char* file;
  const char* in;
  const char* out;
  std::optional<double> dt_s;
  Eigen::Index from, to;  // 0-based half-open row range (to = -1: the end)
  bool known_nonlinear;   // a linear model must not be judged sufficient
};

struct Series {
  Eigen::VectorXd u, y;
  double dt_s = 0.0;
};

std::optional<fs::path> data_dir() {
  const char* d = std::getenv("RIG_SHARED_DIR");
  if (!d) return std::nullopt;
  const fs::path p = fs::path(d) / "data";
  return fs::exists(p) ? std::optional<fs::path>(p) : std::nullopt;
}

Series load(const fs::path& file, const char* in, const char* out, std::optional<double> dt_s,
            Eigen::Index from = 0, Eigen::Index to = -1) {
  rig::io::ReadOptions ro;
  ro.columns = {in, out};
  ro.dt_s = dt_s;
  const auto rec = rig::io::read_recording(file, ro);
  const Eigen::Index end = to < 0 ? rec.rows() : to;
  return {rec.column(in).segment(from, end - from), rec.column(out).segment(from, end - from),
          rec.dt_s};
}

Series load(const fs::path& root, const RealCase& c) {
  return load(root / c.file, c.in, c.out, c.dt_s, c.from, c.to);
}

// The model `rig identify --method mmfm` writes (automatic order and delay, default lag window);
// identify()'s data-quality gate is the CLI's and is not applied here.
rig::ident::IdentifyResult fit_linear(const Series& s) {
  rig::ident::IdentifyOptions io;
  io.methods = {rig::ident::IdentMethod::kMmfm};
  io.correlator.lags = std::min<Eigen::Index>(256, s.u.size() / 8);
  return rig::ident::identify(s.u, s.y, s.dt_s, io);
}

dg::DiagnoseResult run_diagnosis(const rig::model::TransferFunction& model, const Series& s,
                                 const dg::DiagnoseOptions& options = {}) {
  return dg::diagnose({model, s.u, s.y, s.dt_s, std::nullopt}, options);
}

void print_hypothesis(const dg::HypothesisFit& h) {
  std::printf("  %s [", h.name().c_str());
  for (const auto& e : h.effects)
    for (double p : e.params) std::printf(" %.4g", p);
  std::printf(" ]: validation fit %.1f -> %.1f, score %+.2f\n", h.validation_fit_before,
              h.validation_fit_after, h.score);
}

// "%.1f" of a fit, "-" without one.
std::string pct(std::optional<double> v) {
  if (!v) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", *v);
  return buf;
}

// model_fit: the identified model's own validation fit (nullopt: the model was not identified).
void print_diagnosis(const std::string& name, std::optional<double> model_fit,
                     const dg::DiagnoseResult& r) {
  const auto* h = r.chosen();
  std::printf(
      "%s: identified model validation fit %s %%; verdict %s; validation fit %.1f -> %s %%; "
      "%.1f s\n  %s\n",
      name.c_str(), pct(model_fit).c_str(), r.verdict.c_str(), r.validation_fit_before_pct,
      pct(h ? std::optional<double>(h->validation_fit_after) : std::nullopt).c_str(), r.elapsed_s,
      r.explanation.c_str());
  for (std::size_t i = 0; i < std::min<std::size_t>(3, r.hypotheses.size()); ++i)
    print_hypothesis(r.hypotheses[i]);
}

// Validation-fit gain of the hypothesis behind the verdict (0 without one), points.
double chosen_gain(const dg::DiagnoseResult& r) {
  const auto* h = r.chosen();
  return h ? h->validation_fit_after - h->validation_fit_before : 0.0;
}

const dg::HypothesisFit* find_single(const dg::DiagnoseResult& r, dg::Effect e) {
  for (const auto& h : r.hypotheses)
    if (h.effects.size() == 1 && h.effects[0].effect == e) return &h;
  return nullptr;
}

TEST(RealData, VerdictsOnPublicBenchmarks) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  const RealCase cases[] = {
      {"daisy/dryer.dat", "1", "2", 0.08, 0, -1, false},
      {"nonlinear_benchmarks/silverbox/SNLS80mV.csv", "V1", "V2", 1.0 / 610.35, 40650, 60650, true},
      // On its own estimation record the verdict is printed, not asserted (the model was
      // fitted to it); CascadedTanksClippedOutput below diagnoses the validation record.
      {"nonlinear_benchmarks/cascaded_tanks/dataBenchmark.csv", "uEst", "yEst", std::nullopt, 0, -1,
       false},
      {"nonlinear_benchmarks/wiener_hammerstein_2009/WienerHammerBenchmark.csv", "uBenchMark",
       "yBenchMark", 1.0 / 51200.0, 5200, 25200, true},
      {"daisy/heating_system.dat", "2", "3", 2.0, 0, -1, false},
  };
  for (const auto& c : cases) {
    try {
      const Series s = load(*root, c);
      const auto id = fit_linear(s);
      const auto r = run_diagnosis(id.model, s);
      print_diagnosis(c.file, id.validation_fit_pct, r);
      if (c.known_nonlinear) {
        EXPECT_NE(r.verdict, "none") << c.file;
      }
    } catch (const std::exception& e) {
      std::printf("%s: not diagnosed: %s\n", c.file, e.what());
      ADD_FAILURE() << c.file << ": " << e.what();
    }
  }
}

// Cascaded tanks (README A2): the model from the estimation record, the diagnosis on the
// validation record, whose output sits at exactly 10.0 in 37 samples (the overflow and the
// sensor's range). The clip is found and every model compared through it; with it the
// level-dependent gain of the outflow is looked for and named, at the output.
TEST(RealData, CascadedTanksClippedOutput) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  const fs::path csv = *root / "nonlinear_benchmarks/cascaded_tanks/dataBenchmark.csv";
  const auto id = fit_linear(load(csv, "uEst", "yEst", std::nullopt));
  const auto r = run_diagnosis(id.model, load(csv, "uVal", "yVal", std::nullopt));
  print_diagnosis("cascaded tanks (uEst/yEst model, uVal/yVal record)", id.validation_fit_pct, r);
  EXPECT_EQ(r.problem.output_clip.side, +1);
  EXPECT_EQ(r.problem.output_clip.level, 10.0);
  EXPECT_EQ(r.problem.output_clip.samples, 37);
  EXPECT_LE(r.baseline_yhat.maxCoeff() + r.problem.y_level, 10.0 + 1e-9);
  EXPECT_EQ(r.verdict, "static_nonlinearity");
  ASSERT_NE(r.chosen(), nullptr);
  EXPECT_EQ(r.chosen()->effects.front().place, dg::Place::kOutput);
  EXPECT_GT(chosen_gain(r), 2.0);
}

// EMPS (README A4): motor force command vir (V) -> motor position qm (m), 1 kHz, closed loop.
// Model from DATA_EMPS, diagnosis on DATA_EMPS_PULSES (not seen by the model). The identified
// model's damping already holds the friction's equivalent viscous part, so the verdict is
// not asserted to be coulomb_friction (printed); the linear model must not pass.
TEST(RealData, EmpsPositioningAxisOnPulsesRecord) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  const fs::path dir = *root / "nonlinear_benchmarks/emps";
  const auto id = fit_linear(load(dir / "DATA_EMPS.csv", "vir", "qm", 1e-3));
  const auto r = run_diagnosis(id.model, load(dir / "DATA_EMPS_PULSES.csv", "vir", "qm", 1e-3));
  print_diagnosis("EMPS (DATA_EMPS model, DATA_EMPS_PULSES record)", id.validation_fit_pct, r);
  if (const auto* cf = find_single(r, dg::Effect::kCoulombFriction)) print_hypothesis(*cf);
  EXPECT_NE(r.verdict, "none");
  EXPECT_NE(r.verdict, "unexplained");
  EXPECT_GT(chosen_gain(r), 10.0) << r.verdict;
}

// The coulomb_friction hypothesis on the EMPS rigid body with the reference parameters of
// Janot, Gautier & Brunot (2019): M = 95.1089 kg, Fv = 203.5034 N s/m, Fc = 20.3935 N,
// gtau = 35.1507 N/V. qm/vir = (gtau/M) / ((s + p)(s + Fv/M)); the integrator is moved to
// p = 0.05 rad/s (diagnose needs a stable model; 1/p = 20 s, about the record length).
// Tolerance 30 % on Fc: the model has no offset force (-3.2 N), a leak for the integrator,
// and tanh instead of sign.
TEST(RealData, EmpsCoulombFrictionOnReferenceRigidBody) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  constexpr double kMass_kg = 95.1089, kViscous_ns_m = 203.5034, kCoulomb_n = 20.3935;
  constexpr double kGtau_n_v = 35.1507, kLeak_rad_s = 0.05;
  rig::model::TransferFunction model;
  model.num = Eigen::VectorXd::Constant(1, kGtau_n_v / kMass_kg);
  model.den = Eigen::Vector3d(1.0, kViscous_ns_m / kMass_kg + kLeak_rad_s,
                              kLeak_rad_s * kViscous_ns_m / kMass_kg);
  dg::DiagnoseOptions opt;
  opt.effects = {dg::Effect::kCoulombFriction};
  opt.try_pairs = false;
  const auto r = run_diagnosis(
      model, load(*root / "nonlinear_benchmarks/emps/DATA_EMPS_PULSES.csv", "vir", "qm", 1e-3),
      opt);
  print_diagnosis("EMPS reference rigid body + coulomb_friction", std::nullopt, r);
  ASSERT_EQ(r.verdict, "coulomb_friction");
  const double fc_n = r.chosen()->effects[0].params[0] * kGtau_n_v;
  std::printf("  friction %.1f N (reference %.1f N)\n", fc_n, kCoulomb_n);
  EXPECT_NEAR(fc_n, kCoulomb_n, 0.3 * kCoulomb_n);
  EXPECT_GT(chosen_gain(r), 50.0);
}

// Silverbox (README A1): model from the multisine training part, diagnosis on the arrow
// (amplitude rising to the end, not seen by the model). The cubic hardening stiffness is what
// the linear model misses: nonlinear_stiffness started inside the range where the augmented
// model stays stable at the arrow's peak (5.6 output standard deviations) must recover it.
TEST(RealData, SilverboxArrowFromMultisineModel) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  const fs::path file = *root / "nonlinear_benchmarks/silverbox/SNLS80mV.csv";
  const double dt_s = 1.0 / 610.35;
  const auto id = fit_linear(load(file, "V1", "V2", dt_s, 40650, 60650));
  const auto r = run_diagnosis(id.model, load(file, "V1", "V2", dt_s, 100, 40575));
  print_diagnosis("Silverbox arrow", id.validation_fit_pct, r);
  EXPECT_NE(r.verdict, "none");
  EXPECT_GT(chosen_gain(r), 2.0) << r.verdict;

  const dg::AppliedEffect start{dg::Effect::kNonlinearStiffness, {0.01}};
  const auto h = dg::fit_hypothesis(r.problem, {{start}}, r.baseline_yhat, dg::FitOptions{});
  print_hypothesis(h);
  EXPECT_GT(h.effects[0].params[0], 0.0) << "hardening";
  EXPECT_GT(h.validation_fit_after - h.validation_fit_before, 8.0);
}

// CE8 coupled electric drives (README A3): PRBS +-1 record for the model, the +-1.5 record
// diagnosed. The pulse counter reads |omega|: for a zero-mean PRBS the output is nearly
// uncorrelated with the input, so the linear model explains almost nothing. The verdict is
// printed, not asserted: every test of the location step is second order in u and cannot
// see an even output nonlinearity (docs/diagnose.md, real records).
TEST(RealData, CoupledElectricDrivesPrbs) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  const fs::path file = *root / "nonlinear_benchmarks/coupled_electric_drives/DATAPRBS.csv";
  const auto id = fit_linear(load(file, "u1", "z1", 0.02));
  const auto r = run_diagnosis(id.model, load(file, "u2", "z2", 0.02));
  print_diagnosis("CE8 PRBS (+-1 model, +-1.5 record)", id.validation_fit_pct, r);
  EXPECT_LT(id.validation_fit_pct, 20.0);
  EXPECT_LT(r.validation_fit_before_pct, 20.0);
}

// Short unseen-part diagnoses of records whose linear model misses something the README
// names: F-16 (model from Level 1, diagnosed at Level 7: amplitude-dependent stiffness and
// damping), Bouc-Wen (hysteresis; simulated control case), heat exchanger (flow-dependent
// gain). The linear model must not be judged sufficient.
TEST(RealData, UnseenPartsOfNonlinearRecords) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  struct Pair {
    RealCase model, record;
  };
  const Pair pairs[] = {
      {{"nonlinear_benchmarks/f16_gvt/F16Data_FullMSine_Level1.csv", "Force", "Acceleration2",
        std::nullopt, 0, 16384, true},
       {"nonlinear_benchmarks/f16_gvt/F16Data_FullMSine_Level7.csv", "Force", "Acceleration2",
        std::nullopt, 0, 16384, true}},
      {{"nonlinear_benchmarks/bouc_wen_sim/val_multisine.csv", "u", "y", 1.0 / 750.0, 0, 4096,
        true},
       {"nonlinear_benchmarks/bouc_wen_sim/val_multisine.csv", "u", "y", 1.0 / 750.0, 4096, -1,
        true}},
      {{"daisy/exchanger.dat", "2", "3", 1.0, 0, 2000, true},
       {"daisy/exchanger.dat", "2", "3", 1.0, 2000, -1, true}},
  };
  for (const auto& p : pairs) {
    const auto id = fit_linear(load(*root, p.model));
    const auto r = run_diagnosis(id.model, load(*root, p.record));
    print_diagnosis(std::string(p.record.file) + " from row " + std::to_string(p.record.from),
                    id.validation_fit_pct, r);
    EXPECT_NE(r.verdict, "none") << p.record.file;
  }
}

}  // namespace
