#include "rig/signal/excitation.hpp"

#include <fftw3.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <iostream>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "rig/signal/butterworth.hpp"
#include "rig/signal/correlators.hpp"
#include "rig/signal/fftw_planner.hpp"

namespace rig::signal {
namespace {

double std_dev(const Eigen::VectorXd& x) {
  return std::sqrt((x.array() - x.mean()).square().mean());
}

// One-sided periodogram |X_k|^2, k = 0..n/2 (FFTW r2c).
Eigen::VectorXd periodogram(const Eigen::VectorXd& x) {
  const int n = static_cast<int>(x.size());
  std::vector<double> in(x.data(), x.data() + n);
  std::vector<fftw_complex> out(static_cast<size_t>(n / 2 + 1));
  std::lock_guard<std::mutex> lock(fftw_planner_mutex());
  fftw_plan plan = fftw_plan_dft_r2c_1d(n, in.data(), out.data(), FFTW_ESTIMATE);
  fftw_execute(plan);
  fftw_destroy_plan(plan);
  Eigen::VectorXd p(n / 2 + 1);
  for (int k = 0; k <= n / 2; ++k) p[k] = out[k][0] * out[k][0] + out[k][1] * out[k][1];
  return p;
}

TEST(GaussianExcitation, ExactSigmaDeterministicAndGaussian) {
  const GaussianOptions o{.n = 1 << 17, .dt_s = 0.01, .bandwidth_hz = 4.0, .sigma = 0.6, .seed = 7};
  std::cout << "[seed] gaussian seed=" << o.seed << "\n";
  const Eigen::VectorXd x = gaussian_excitation(o);
  EXPECT_NEAR(std_dev(x), 0.6, 1e-12);
  EXPECT_NEAR(x.mean(), 0.0, 1e-12);
  EXPECT_EQ((gaussian_excitation(o) - x).cwiseAbs().maxCoeff(), 0.0);
  GaussianOptions other = o;
  other.seed = 8;
  EXPECT_GT((gaussian_excitation(other) - x).cwiseAbs().maxCoeff(), 0.1);
  // Kurtosis 3 for a Gaussian. Band-limiting to 4 of 50 Hz leaves ~n*8/100 = 10^4 effective
  // samples, standard error sqrt(24/10^4) = 0.05: 0.25 is a 5-sigma bound.
  const double kurtosis = (x.array() / 0.6).pow(4).mean();
  EXPECT_NEAR(kurtosis, 3.0, 0.25);
}

// The spectrum follows |H(f)|^2 of the Butterworth filter: the share of power below the
// corner matches the filter's share (2 % absolute: ~2600 periodogram bins in band, each
// exponentially distributed) and almost nothing lies above twice the corner.
TEST(GaussianExcitation, SpectrumStaysInBand) {
  const GaussianOptions o{.n = 1 << 16, .dt_s = 0.01, .bandwidth_hz = 4.0, .seed = 3};
  const Eigen::VectorXd p = periodogram(gaussian_excitation(o));
  const ButterworthLowPass filter(o.filter_order, o.bandwidth_hz, o.dt_s);
  const double df = 1.0 / (static_cast<double>(o.n) * o.dt_s);
  double measured_in = 0, measured_all = 0, measured_above = 0, model_in = 0, model_all = 0;
  for (Eigen::Index k = 1; k < p.size(); ++k) {
    const double f = static_cast<double>(k) * df;
    const double h2 = std::norm(filter.response(f));
    measured_all += p[k];
    model_all += h2;
    if (f <= o.bandwidth_hz) {
      measured_in += p[k];
      model_in += h2;
    }
    if (f > 2.0 * o.bandwidth_hz) measured_above += p[k];
  }
  EXPECT_NEAR(measured_in / measured_all, model_in / model_all, 0.02);
  EXPECT_GT(measured_in / measured_all, 0.85);
  EXPECT_LT(measured_above / measured_all, 0.005);
  EXPECT_NEAR(std::abs(filter.response(o.bandwidth_hz)), std::sqrt(0.5), 1e-12);  // -3 dB at fc
}

TEST(GaussianExcitation, ClippingKeepsSigmaAndBoundsPeaks) {
  const GaussianOptions o{.n = 20000, .sigma = 2.0, .clip_sigma = 2.5, .seed = 5};
  const Eigen::VectorXd x = gaussian_excitation(o);
  EXPECT_NEAR(std_dev(x), 2.0, 1e-12);
  EXPECT_LE(x.cwiseAbs().maxCoeff(), 5.0 * (1.0 + 1e-12));
  EXPECT_GT((x.array().abs() >= 5.0 * (1.0 - 1e-9)).count(), 20);  // clipping did happen
  EXPECT_THROW(gaussian_excitation({.clip_sigma = 0.9}), std::invalid_argument);
  EXPECT_THROW(gaussian_excitation({.dt_s = 0.01, .bandwidth_hz = 60.0}), std::invalid_argument);
}

TEST(GaussianExcitation, DefaultBandwidthIsTwiceTheResonance) {
  const Eigen::VectorXd by_resonance = gaussian_excitation({.n = 3000, .resonance_hz = 3.0});
  const Eigen::VectorXd explicit_band = gaussian_excitation({.n = 3000, .bandwidth_hz = 6.0});
  EXPECT_EQ((by_resonance - explicit_band).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT((gaussian_excitation({.n = 3000, .bandwidth_hz = 5.0}) - explicit_band).norm(), 1.0);
}

// Unit DC gain, -3 dB at the corner and order-n roll-off (|H(10 fc)| ~ 10^-n) for odd and even n.
// fc T = 0.001 is a badly conditioned case on purpose: each section's 1 + a1 + a2 ~ (wc T)^2
// ~ 4e-5, so rounding of 1e-16 in the coefficients moves the DC gain by ~1e-11 per section.
TEST(Butterworth, CornerDcGainAndRollOff) {
  for (int order : {1, 2, 3, 4, 5}) {
    ButterworthLowPass f(order, 1.0, 0.001);
    EXPECT_NEAR(std::abs(f.response(0.0)), 1.0, 1e-10) << order;
    EXPECT_NEAR(std::abs(f.response(1.0)), std::sqrt(0.5), 1e-12) << order;
    EXPECT_NEAR(std::log10(std::abs(f.response(10.0))), -order, 0.05) << order;
    const Eigen::VectorXd step = f.process(Eigen::VectorXd::Ones(20000));
    EXPECT_NEAR(step.tail(1)[0], 1.0, 1e-9) << order;
  }
  EXPECT_THROW(ButterworthLowPass(9, 1.0, 0.001), std::invalid_argument);
  EXPECT_THROW(ButterworthLowPass(2, 600.0, 0.001), std::invalid_argument);
}

// Primitive over GF(2): x^(2^n-1) = 1 mod p(x) and x^((2^n-1)/q) != 1 for every prime q | 2^n-1.
std::uint64_t mulmod(std::uint64_t a, std::uint64_t b, std::uint64_t poly, int n) {
  std::uint64_t r = 0;
  for (; b; b >>= 1) {
    if (b & 1) r ^= a;
    a <<= 1;
    if (a >> n & 1) a ^= poly;
  }
  return r;
}
std::uint64_t x_pow(std::uint64_t e, std::uint64_t poly, int n) {
  std::uint64_t result = 1, base = 2;
  for (; e; e >>= 1) {
    if (e & 1) result = mulmod(result, base, poly, n);
    base = mulmod(base, base, poly, n);
  }
  return result;
}

TEST(PrbsExcitation, EveryTapSetIsPrimitive) {
  for (int n = 2; n <= 31; ++n) {
    std::uint64_t poly = (std::uint64_t{1} << n) | 1;
    for (int t : prbs_taps(n)) poly |= std::uint64_t{1} << t;
    const std::uint64_t order = (std::uint64_t{1} << n) - 1;
    EXPECT_EQ(x_pow(order, poly, n), 1U) << "n " << n;
    std::uint64_t rest = order;
    for (std::uint64_t q = 2; q * q <= rest || rest > 1; ++q) {
      if (q * q > rest) q = rest;  // what remains is prime
      if (rest % q != 0) continue;
      while (rest % q == 0) rest /= q;
      EXPECT_NE(x_pow(order / q, poly, n), 1U) << "n " << n << " factor " << q;
    }
  }
}

TEST(PrbsExcitation, GeneratorHasMaximalPeriod) {
  for (int n = 2; n <= 20; ++n) {
    const Eigen::Index period = (Eigen::Index{1} << n) - 1;
    const Eigen::VectorXd x = prbs_excitation({.n = 2 * period, .register_length = n});
    EXPECT_EQ(x.head(period), x.tail(period)) << "n " << n;
    for (Eigen::Index q = 1; q < period; ++q) {
      if (period % q != 0) continue;
      EXPECT_NE(x.head(period - q), x.segment(q, period - q)) << "n " << n << " period " << q;
    }
    EXPECT_EQ((x.head(period).array() > 0).count(), period / 2 + 1) << "n " << n;
  }
}

TEST(PrbsExcitation, CircularAutocorrelationIsTwoValued) {
  for (int n : {7, 10}) {
    const Eigen::Index period = (Eigen::Index{1} << n) - 1;
    const double a = 1.5;
    const Eigen::VectorXd x =
        prbs_excitation({.n = period, .register_length = n, .amplitude = a, .seed = 9});
    EXPECT_NEAR(x.mean(), a / static_cast<double>(period), 1e-12);
    for (Eigen::Index k = 0; k < period; ++k) {
      double r = 0.0;
      for (Eigen::Index i = 0; i < period; ++i) r += x[i] * x[(i + k) % period];
      r /= static_cast<double>(period);
      ASSERT_NEAR(r, k == 0 ? a * a : -a * a / static_cast<double>(period), 1e-12)
          << "n " << n << " k " << k;
    }
  }
}

TEST(PrbsExcitation, DividerHoldsBitsAndSeedShiftsPhase) {
  const Eigen::VectorXd slow =
      prbs_excitation({.n = 3 * 127, .register_length = 7, .clock_divider = 3});
  const Eigen::VectorXd fast = prbs_excitation({.n = 127, .register_length = 7});
  for (Eigen::Index i = 0; i < slow.size(); ++i) ASSERT_EQ(slow[i], fast[i / 3]);
  const Eigen::VectorXd other = prbs_excitation({.n = 127, .register_length = 7, .seed = 40});
  EXPECT_NE(other, fast);
  bool is_shift = false;
  for (Eigen::Index s = 0; s < 127 && !is_shift; ++s) {
    bool same = true;
    for (Eigen::Index i = 0; i < 127 && same; ++i) same = other[i] == fast[(i + s) % 127];
    is_shift = same;
  }
  EXPECT_TRUE(is_shift);
  EXPECT_THROW(prbs_taps(1), std::invalid_argument);
  EXPECT_THROW(prbs_taps(32), std::invalid_argument);
  EXPECT_THROW(prbs_excitation({.clock_divider = 0}), std::invalid_argument);
}

TEST(MultisineExcitation, SchroederPhasesKeepTheCrestFactorLow) {
  const Eigen::Index n = 1024;
  const MultisineOptions o{.n = n, .frequencies_hz = harmonic_frequencies_hz(n, 0.01, 1, 31)};
  const double schroeder = crest_factor(multisine_excitation(o));
  MultisineOptions random = o;
  random.phases = MultisinePhases::kRandom;
  random.seed = 4;
  const double random_crest = crest_factor(multisine_excitation(random));
  std::cout << "crest factor: Schroeder " << schroeder << ", random phases " << random_crest
            << ", zero phases " << std::sqrt(2.0 * 31) << "\n";
  EXPECT_LT(schroeder, 1.9);
  EXPECT_GT(schroeder, std::sqrt(2.0) - 1e-9);  // a single sine's crest factor is the floor
  EXPECT_LT(schroeder, random_crest);
}

// Over whole periods the DFT shows each line with amplitude A_k, and the correlator's estimate
// equals r(tau) = sum A_k^2/2 cos(2 pi f_k tau) to rounding (cross terms cancel exactly).
TEST(MultisineExcitation, LinesAndAutocorrelationAreAnalytic) {
  const Eigen::Index n0 = 128, lags = 64, periods = 20;
  const double dt_s = 0.01;
  const std::vector<double> f = harmonic_frequencies_hz(n0, dt_s, 3, 9);
  const std::vector<double> amp = {1.0, 0.5, 0.25, 2.0, 1.0, 0.7, 0.3};
  const MultisineOptions o{.n = lags - 1 + periods * n0,
                           .dt_s = dt_s,
                           .frequencies_hz = f,
                           .amplitudes = amp,
                           .phases = MultisinePhases::kRandom,
                           .seed = 12};
  const Eigen::VectorXd x = multisine_excitation(o);
  const Eigen::VectorXd p = periodogram(x.head(periods * n0));
  for (size_t k = 0; k < f.size(); ++k) {
    const auto bin = static_cast<Eigen::Index>((k + 3) * periods);
    EXPECT_NEAR(2.0 * std::sqrt(p[bin]) / static_cast<double>(periods * n0), amp[k], 1e-9);
  }
  const Correlation r = auto_correlation(x, {.lags = lags, .zero_index = 20, .dt_s = dt_s});
  for (Eigen::Index i = 0; i < lags; ++i) {
    double analytic = 0.0;
    for (size_t k = 0; k < f.size(); ++k) {
      analytic += amp[k] * amp[k] / 2.0 * std::cos(2.0 * std::numbers::pi * f[k] * r.lag_s(i));
    }
    EXPECT_NEAR(r.r[i], analytic, 1e-10) << "lag " << i;
  }
  MultisineOptions scaled = o;
  scaled.rms = 0.25;
  EXPECT_NEAR(multisine_excitation(scaled).norm() / std::sqrt(o.n), 0.25, 1e-12);
  EXPECT_THROW(multisine_excitation({.frequencies_hz = {60.0}}), std::invalid_argument);
  EXPECT_THROW(multisine_excitation({.frequencies_hz = {1.0}, .amplitudes = {1.0, 2.0}}),
               std::invalid_argument);
}

}  // namespace
}  // namespace rig::signal
