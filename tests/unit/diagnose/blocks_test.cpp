#include "rig/diagnose/blocks.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "concealed.hpp"
#include "rig/signal/excitation.hpp"

namespace rig::diagnose {
namespace {

Eigen::VectorXd v(std::initializer_list<double> x) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(x.size()));
  Eigen::Index i = 0;
  for (double e : x) out(i++) = e;
  return out;
}

TEST(Blocks, DeadbandRemovesTheBandAndShiftsOutside) {
  const Eigen::VectorXd y = deadband(v({-2.0, -0.5, 0.0, 0.4, 1.5}), 0.5);
  EXPECT_DOUBLE_EQ(y(0), -1.5);
  EXPECT_DOUBLE_EQ(y(1), 0.0);
  EXPECT_DOUBLE_EQ(y(3), 0.0);
  EXPECT_DOUBLE_EQ(y(4), 1.0);
}

TEST(Blocks, BacklashHoldsUntilThePlayIsTakenUp) {
  // Rise to 2, reverse: the output stays at 1.5 until the input falls below 1.0.
  const Eigen::VectorXd y = backlash(v({0.0, 1.0, 2.0, 1.5, 1.0, 0.0}), 0.5);
  EXPECT_DOUBLE_EQ(y(2), 1.5);
  EXPECT_DOUBLE_EQ(y(3), 1.5);
  EXPECT_DOUBLE_EQ(y(4), 1.5);
  EXPECT_DOUBLE_EQ(y(5), 0.5);
}

TEST(Blocks, SaturationAndRateLimit) {
  const Eigen::VectorXd s = saturate(v({-3.0, 0.2, 3.0}), -1.0, 2.0);
  EXPECT_DOUBLE_EQ(s(0), -1.0);
  EXPECT_DOUBLE_EQ(s(2), 2.0);
  // A unit step through a 10 /s limit at dt = 0.01 climbs 0.1 per sample.
  const Eigen::VectorXd r = rate_limit(v({0.0, 1.0, 1.0, 1.0}), 10.0, 0.01);
  EXPECT_NEAR(r(1), 0.1, 1e-12);
  EXPECT_NEAR(r(3), 0.3, 1e-12);
}

TEST(Blocks, PolyFromRootsRebuildsAQuadratic) {
  Eigen::VectorXcd roots(2);
  roots << std::complex<double>(-1.0, 2.0), std::complex<double>(-1.0, -2.0);
  const Eigen::VectorXd p = poly_from_roots(roots);  // s^2 + 2 s + 5
  EXPECT_NEAR(p(0), 1.0, 1e-12);
  EXPECT_NEAR(p(1), 2.0, 1e-12);
  EXPECT_NEAR(p(2), 5.0, 1e-12);
}

TEST(Blocks, FeedbackSimulationWithoutFeedbackMatchesExactSimulation) {
  const model::TransferFunction tf = nominal_genset_model();
  signal::GaussianOptions go;
  go.n = 6000, go.dt_s = 0.01, go.bandwidth_hz = 4.0, go.seed = 3;
  const Eigen::VectorXd u = signal::gaussian_excitation(go);
  const Eigen::VectorXd exact = model::simulate(tf, u, 0.01);
  const Eigen::VectorXd loop =
      simulate_with_feedback(tf, u, 0.01, [](double, double) { return 0.0; });
  // Mid-sample zero-order hold versus first-order hold: second order in dt.
  EXPECT_LT((exact - loop).norm() / exact.norm(), 5e-3);
}

// Above the fixed state sizes (14) the loop runs at run-time size: the same answer. Sixteen
// lags of 0.5 s in series (a unit static gain; faster ones take the monic denominator beyond
// what a companion matrix holds, as in model::simulate's scaled time).
TEST(Blocks, FeedbackSimulationAboveTheFixedSizesMatchesExactSimulation) {
  Eigen::VectorXd den = v({1.0});
  for (int i = 0; i < 16; ++i) den = poly_multiply(den, v({0.5, 1.0}));
  const model::TransferFunction tf{v({1.0}), den, 0.0};
  signal::GaussianOptions go;
  go.n = 6000, go.dt_s = 0.01, go.bandwidth_hz = 0.5, go.seed = 5;
  const Eigen::VectorXd u = signal::gaussian_excitation(go);
  const Eigen::VectorXd exact = model::simulate(tf, u, 0.01);
  const Eigen::VectorXd loop =
      simulate_with_feedback(tf, u, 0.01, [](double, double) { return 0.0; });
  EXPECT_LT((exact - loop).norm() / exact.norm(), 5e-3);
}

TEST(Blocks, CubicFeedbackStiffensTheResponse) {
  model::TransferFunction tf{v({1.0}), v({1.0, 0.5, 1.0}), 0.0};  // unit static gain
  const Eigen::VectorXd u = Eigen::VectorXd::Constant(8000, 2.0);
  // Static equilibrium z = u - k3 z^3 with k3 = 0.25: z^3/4 + z - 2 = 0, solved by Newton.
  double zs = 1.0;
  for (int i = 0; i < 50; ++i) zs -= (0.25 * zs * zs * zs + zs - 2.0) / (0.75 * zs * zs + 1.0);
  const Eigen::VectorXd z =
      simulate_with_feedback(tf, u, 0.01, [](double x, double) { return 0.25 * x * x * x; });
  EXPECT_NEAR(z(7999), zs, 1e-6);
  EXPECT_LT(zs, 2.0);
}

TEST(Blocks, ZeroPhaseSmootherKeepsAConstantAndKillsAFastSine) {
  Eigen::VectorXd x(5000);
  for (Eigen::Index k = 0; k < x.size(); ++k)
    x(k) = 3.0 + std::sin(2.0 * 3.14159 * 5.0 * 0.01 * static_cast<double>(k));
  const Eigen::VectorXd s = smooth_zero_phase(x, 5.0, 0.01);
  EXPECT_NEAR(s(2500), 3.0, 0.01);
}

// Bouc-Wen: a sustained movement lags by the half-width, a reversal returns linearly when
// the shape ratio is 1 (a play), and the loop encloses area (it is hysteretic).
TEST(Blocks, BoucWenLagsByItsHalfWidthAndEnclosesALoop) {
  const int n = 2000;
  Eigen::VectorXd u(n);
  for (int k = 0; k < n; ++k) u(k) = std::sin(2.0 * M_PI * k / 1000.0);  // two cycles
  const double w = 0.1;
  const Eigen::VectorXd v = bouc_wen(u, w, 1.0);
  // At the end of the first rise (k = 250, u = 1) v lags by almost w.
  EXPECT_NEAR(u(250) - v(250), w, 0.01 * w);
  // At the zero crossings of the second cycle the rising and falling outputs differ.
  EXPECT_GT(std::abs(v(1000) - v(1500)), 1.5 * w);
  // Never more than w behind.
  EXPECT_LE((u - v).cwiseAbs().maxCoeff(), w * (1.0 + 1e-12));
  // Just after the reversal at the bottom (k = 750) the play holds (its lag shrinks only as u
  // rises), while a rounder loop (shape -0.5) already follows: its lag shrinks faster.
  const Eigen::VectorXd round = bouc_wen(u, w, -0.5);
  EXPECT_LT(std::abs(u(770) - round(770)), std::abs(u(770) - v(770)) - 0.01 * w);
}

}  // namespace
}  // namespace rig::diagnose
