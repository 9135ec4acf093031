#include "rig/fra/lockin.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rig/fra/frf.hpp"
#include "second_order.hpp"

namespace rig::fra {
namespace {

constexpr double kDt = 0.01;

struct Record {
  Eigen::VectorXd u, y;
  double t0_s;
};

// Settles for settle_s, then keeps `cycles` whole cycles; adds white noise of
// noise_fraction times the response amplitude to y.
Record sine_record(const testing::SecondOrderDelay& g, double f, double settle_s, int cycles,
                   double noise_fraction, unsigned seed) {
  const double amp = 0.5;
  const auto settle_n =
      static_cast<Eigen::Index>(std::llround(std::ceil(settle_s * f) / (f * kDt)));
  const auto keep = static_cast<Eigen::Index>(std::llround(cycles / (f * kDt)));
  const Eigen::VectorXd y_all = testing::exact_sine_response(g, amp, f, kDt, settle_n + keep);
  Record r;
  r.t0_s = static_cast<double>(settle_n) * kDt;
  r.u.resize(keep);
  for (Eigen::Index i = 0; i < keep; ++i) {
    r.u(i) = amp * std::sin(2.0 * std::numbers::pi * f * (r.t0_s + static_cast<double>(i) * kDt));
  }
  r.y = y_all.tail(keep);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_fraction * amp * std::abs(g.response(f)));
  for (Eigen::Index i = 0; i < keep; ++i) r.y(i) += noise(rng);
  return r;
}

TEST(LockIn, MatchesAnalyticSecondOrderWithDelay) {
  const testing::SecondOrderDelay g;  // 40 kW/%, 2 Hz, zeta 0.1, 60 ms
  unsigned seed = 11;
  for (double f : {0.3, 1.0, 1.9, 2.0, 3.5, 7.0, 10.0}) {
    SCOPED_TRACE("f = " + std::to_string(f) + " Hz, seed " + std::to_string(seed));
    const Record r = sine_record(g, f, 10.0, std::max(10, static_cast<int>(5 * f)), 0.01, seed++);
    const LockInPoint p = lock_in(r.u, r.y, f, kDt, r.t0_s);
    const std::complex<double> h = g.response(f);
    EXPECT_NEAR(model::to_db(std::abs(p.ratio)), model::to_db(std::abs(h)), 0.05);
    EXPECT_NEAR(model::wrap_deg((std::arg(p.ratio) - std::arg(h)) * 180.0 / std::numbers::pi), 0.0,
                0.3);
    EXPECT_GT(p.coherence, 0.999);
    EXPECT_LT(p.y.distortion(), 1e-4);
  }
}

TEST(LockIn, DistortionFigureDetectsAddedHarmonic) {
  const testing::SecondOrderDelay g;
  const double f = 1.0;
  Record r = sine_record(g, f, 10.0, 20, 0.01, 5);
  const double y1 = 0.5 * std::abs(g.response(f));
  const LockInPoint clean = lock_in(r.u, r.y, f, kDt, r.t0_s);
  // A 5 % second harmonic: distortion = 0.05^2 = 2.5e-3 of the fundamental power.
  for (Eigen::Index i = 0; i < r.y.size(); ++i) {
    const double t = r.t0_s + static_cast<double>(i) * kDt;
    r.y(i) += 0.05 * y1 * std::sin(2.0 * 2.0 * std::numbers::pi * f * t + 0.3);
  }
  const LockInPoint dirty = lock_in(r.u, r.y, f, kDt, r.t0_s);
  EXPECT_LT(clean.y.distortion(), 1e-4);
  EXPECT_NEAR(dirty.y.distortion(), 2.5e-3, 0.25e-3);
  EXPECT_NEAR(std::abs(dirty.y.harmonics[1]), 0.05 * y1, 0.005 * y1);
  // The harmonic does not leak into the fundamental.
  EXPECT_NEAR(model::to_db(std::abs(dirty.ratio)), model::to_db(std::abs(clean.ratio)), 0.01);
  // Noise figure: residual variance / fundamental power = 0.01^2 / 0.5.
  EXPECT_NEAR(clean.y.noise_ratio(), 2e-4, 0.3e-4);
}

TEST(LockIn, DriftTermKeepsRampOutOfFundamental) {
  const testing::SecondOrderDelay g;
  const double f = 0.5;
  Record r = sine_record(g, f, 10.0, 8, 0.0, 1);
  const LockInPoint ref = lock_in(r.u, r.y, f, kDt, r.t0_s);
  for (Eigen::Index i = 0; i < r.y.size(); ++i)
    r.y(i) += 3500.0 + 0.8 * static_cast<double>(i) * kDt;
  const LockInPoint drifting = lock_in(r.u, r.y, f, kDt, r.t0_s);
  EXPECT_NEAR(std::abs(drifting.ratio - ref.ratio), 0.0, 1e-6 * std::abs(ref.ratio));
  EXPECT_NEAR(drifting.y.drift_per_s, 0.8, 1e-6);
  // c0 is the value at the window's mid-point.
  const double t_mid_rel_s = 0.5 * static_cast<double>(r.y.size() - 1) * kDt;
  EXPECT_NEAR(drifting.y.mean, ref.y.mean + 3500.0 + 0.8 * t_mid_rel_s, 1e-6);
}

TEST(LockIn, RejectsShortOrMismatchedRecords) {
  EXPECT_THROW(lock_in(Eigen::VectorXd::Zero(10), Eigen::VectorXd::Zero(11), 1.0, kDt),
               std::invalid_argument);
  EXPECT_THROW(fit_harmonics(Eigen::VectorXd::Zero(5), 1.0, kDt), std::invalid_argument);
  EXPECT_THROW(fit_harmonics(Eigen::VectorXd::Zero(500), 0.0, kDt), std::invalid_argument);
}

}  // namespace
}  // namespace rig::fra
