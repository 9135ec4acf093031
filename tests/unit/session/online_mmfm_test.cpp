#include "rig/session/online_mmfm.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rig/model/transfer_function.hpp"
#include "rig/session/pilot.hpp"
#include "rig/signal/excitation.hpp"

namespace rig::session {
namespace {

// H(s) = 46 wn^2 e^{-0.06 s} / (s^2 + 2 zeta wn s + wn^2), fn 2 Hz, zeta 0.1 (kW per %).
model::TransferFunction plant() {
  const double wn = 2.0 * M_PI * 2.0;
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, 46.0 * wn * wn);
  tf.den = Eigen::Vector3d(1.0, 2.0 * 0.1 * wn, wn * wn);
  tf.delay_s = 0.06;
  return tf;
}

// 400 s of band-limited excitation (seed 11) through plant() with 2 kW rms noise (seed 12).
struct Record {
  Eigen::VectorXd u, y;
};
Record record(double dt) {
  signal::GaussianOptions g;
  g.n = 40000;
  g.dt_s = dt;
  g.bandwidth_hz = 4.0;
  g.sigma = 0.2;
  g.seed = 11;
  Record r;
  r.u = signal::gaussian_excitation(g);
  r.y = model::simulate(plant(), r.u, dt);
  std::mt19937 gen(12);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (Eigen::Index i = 0; i < r.y.size(); ++i) r.y(i) += noise(gen);
  return r;
}

TEST(OnlineMmfm, ConvergesToTheSimulatedPlantWithStandardErrors) {
  const double dt = 0.01;
  const Record rec = record(dt);
  const Eigen::VectorXd& u = rec.u;
  const Eigen::VectorXd& y = rec.y;
  OnlineMmfmOptions o;
  o.correlator.dt_s = dt;
  o.block_samples = 2048;
  o.ac_coupling_rc_s = 1.6;
  OnlineMmfm online(o);
  int blocks = 0;
  for (Eigen::Index i = 0; i < u.size(); ++i) blocks += online.push(u(i), y(i)).has_value();
  EXPECT_EQ(blocks, static_cast<int>(u.size() / 2048));
  ASSERT_EQ(online.history().size(), static_cast<std::size_t>(blocks));
  const auto r = online.final_result();
  ASSERT_TRUE(r.derived.valid);
  EXPECT_NEAR(r.derived.gain, 46.0, 46.0 * 0.05);
  EXPECT_NEAR(r.derived.fn_hz, 2.0, 0.04);
  EXPECT_NEAR(r.derived.zeta, 0.1, 0.015);
  EXPECT_NEAR(r.delay_s, 0.06, 0.01);
  // The asymptotic standard errors are finite and cover the truth within 4 of them.
  EXPECT_GT(r.derived.fn_hz_std, 0.0);
  EXPECT_LT(std::abs(r.derived.fn_hz - 2.0), 4.0 * r.derived.fn_hz_std + 0.005);
  EXPECT_TRUE(online.converged());
}

// The worker thread sees the same correlations as the synchronous path: after finish() the
// final model and its standard errors are the same numbers.
TEST(OnlineMmfm, AsynchronousEstimatesMatchTheSynchronousOnes) {
  const double dt = 0.01;
  const Record rec = record(dt);
  OnlineMmfmOptions o;
  o.correlator.dt_s = dt;
  o.block_samples = 2048;
  o.ac_coupling_rc_s = 1.6;
  OnlineMmfm sync(o);
  o.asynchronous = true;
  OnlineMmfm async(o);
  int returned = 0;
  for (Eigen::Index i = 0; i < rec.u.size(); ++i) {
    sync.push(rec.u(i), rec.y(i));
    returned += async.push(rec.u(i), rec.y(i)).has_value();
  }
  async.finish();
  const int blocks = static_cast<int>(rec.u.size() / 2048);
  EXPECT_LE(returned, blocks);  // blocks completed while one was in flight share an estimate
  ASSERT_FALSE(async.history().empty());
  EXPECT_EQ(async.history().back().block, blocks);
  // The live estimates are warm-started from the previous one the worker saw, so they agree
  // to the output-error iteration's tolerance; the final estimate starts cold and agrees
  // exactly.
  const double db = sync.history().back().band_db95, deg = sync.history().back().band_deg95;
  EXPECT_NEAR(async.history().back().band_db95, db, 1e-3 * db);
  EXPECT_NEAR(async.history().back().band_deg95, deg, 1e-3 * deg);
  EXPECT_EQ(async.converged(), sync.converged());
  sync.finish();
  const auto a = async.final_result();
  const auto s = sync.final_result();
  ASSERT_EQ(a.parameters.size(), s.parameters.size());
  for (std::size_t j = 0; j < a.parameters.size(); ++j) {
    EXPECT_EQ(a.parameters[j].value, s.parameters[j].value) << a.parameters[j].name;
    EXPECT_EQ(a.parameters[j].std_error, s.parameters[j].std_error) << a.parameters[j].name;
  }
  EXPECT_EQ(a.derived.fn_hz_std, s.derived.fn_hz_std);
}

TEST(Pilot, PlansTheAmplitudeFromTheMeasuredGain) {
  std::vector<double> u, y;
  std::mt19937 gen(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 5000; ++i) {
    u.push_back(0.2 * n(gen));
    y.push_back(50.0 * u.back() + 3.0 * n(gen));  // gain 50 kW/%, noise 3 kW
  }
  const PilotResult r = analyse_pilot(u, y, {105.0, 0.8, 5.0, 3.0});
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_NEAR(r.gain_kw_per_pct, 50.0, 2.0);
  EXPECT_LE(r.predicted_peak_kw, 0.8 * 105.0 + 1e-9);
  EXPECT_GT(r.planned_std_pct, 0.0);
  // A band that the noise alone fills refuses to plan.
  EXPECT_FALSE(analyse_pilot(u, y, {10.0, 0.8, 5.0, 3.0}).ok);
}

}  // namespace
}  // namespace rig::session
