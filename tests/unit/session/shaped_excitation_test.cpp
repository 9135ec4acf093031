// The shaped excitation (shaped_excitation.hpp) designed from a simulated pilot of a
// Stornoway-like second order plus dead time, then checked by simulating the plant with it:
// the output stays inside the planned part of the band, its spectrum is flat over the lines,
// its crest factor is low, and the input respects the clamp.
#include "rig/session/shaped_excitation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "rig/signal/excitation.hpp"
#include "rig/signal/random.hpp"

namespace rig::session {
namespace {

constexpr double kDt = 0.01;

model::TransferFunction plant() {
  const double wn = 2.0 * M_PI * 2.03, zeta = 0.1;
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, 46.0 * wn * wn);
  tf.den = Eigen::Vector3d(1.0, 2.0 * zeta * wn, wn * wn);
  tf.delay_s = 0.078;
  return tf;
}

// A 30 s Gaussian pilot of 0.3 % std (seed 5) with 5 kW white noise (seed 6).
void pilot(std::vector<double>& u, std::vector<double>& y) {
  signal::GaussianOptions g;
  g.n = 3000;
  g.dt_s = kDt;
  g.bandwidth_hz = 6.0;
  g.sigma = 0.3;
  g.seed = 5;
  const Eigen::VectorXd ue = signal::gaussian_excitation(g);
  const Eigen::VectorXd ye = model::simulate(plant(), ue, kDt);
  signal::Xoshiro256 rng(6);
  u.assign(ue.begin(), ue.end());
  y.resize(u.size());
  for (std::size_t i = 0; i < y.size(); ++i)
    y[i] = ye(static_cast<Eigen::Index>(i)) + 5.0 * rng.normal();
}

ShapedLimits limits() {
  ShapedLimits l;
  l.dt_s = kDt;
  l.band_kw = 105.0;
  l.noise_std_kw = 5.0;
  l.clamp_pct = 5.0;
  l.f_lo_hz = 0.25;
  l.f_hi_hz = 6.0;
  l.seed = 3;
  return l;
}

TEST(ShapedExcitation, FillsThePlannedBandWithAFlatLowCrestOutput) {
  std::vector<double> u, y;
  pilot(u, y);
  const ShapedDesign d = design_shaped_excitation(u, y, limits());
  ASSERT_TRUE(d.ok) << d.reason;
  EXPECT_GT(d.lines, 50);
  EXPECT_LT(d.output_crest, 2.0);  // a Gaussian's is about 4 over a long record
  // Input within the clamp (with its 10 % margin).
  EXPECT_LE(d.period_pct.cwiseAbs().maxCoeff(), kClampFraction * 5.0 + 1e-9);
  // The plant's steady periodic output (third period) inside half the band, noise aside.
  const Eigen::VectorXd x = repeat_period(d.period_pct, 3 * kShapedPeriodSamples);
  const Eigen::VectorXd out = model::simulate(plant(), x, kDt);
  const Eigen::VectorXd last = out.tail(kShapedPeriodSamples);
  const double peak = last.cwiseAbs().maxCoeff();
  EXPECT_LE(peak, kOutputPeakFraction * 105.0);
  EXPECT_GT(peak, 0.5 * kOutputPeakFraction * 105.0);  // and it does fill it
  // Flat output: the line amplitudes of the steady output within +-3 dB of their median
  // away from the capped low-gain end.
  std::vector<double> amp;
  const double f0 = 1.0 / (kShapedPeriodSamples * kDt);
  for (int k = static_cast<int>(std::ceil(0.3 / f0)); k <= static_cast<int>(4.0 / f0); ++k) {
    std::complex<double> c = 0.0;
    for (Eigen::Index t = 0; t < last.size(); ++t) {
      c += last(t) *
           std::polar(1.0, -2.0 * M_PI * k * static_cast<double>(t) / kShapedPeriodSamples);
    }
    amp.push_back(std::abs(c));
  }
  std::vector<double> sorted = amp;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (double a : amp) EXPECT_NEAR(20.0 * std::log10(a / median), 0.0, 3.0);
}

TEST(ShapedExcitation, NoiseThatFillsTheBandRefusesToDesign) {
  std::vector<double> u, y;
  pilot(u, y);
  ShapedLimits l = limits();
  l.noise_std_kw = 20.0;  // 3 sigma = 60 kW > half of the 105 kW band
  const ShapedDesign d = design_shaped_excitation(u, y, l);
  EXPECT_FALSE(d.ok);
  EXPECT_NE(d.reason.find("no room"), std::string::npos) << d.reason;
}

}  // namespace
}  // namespace rig::session
