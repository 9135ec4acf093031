#include "rig/signal/correlators.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <stdexcept>
#include <thread>
#include <vector>

#include "rig/signal/excitation.hpp"
#include "test_data.hpp"

namespace rig::signal {
namespace {

using test::fir;
using test::white;

double max_rel_diff(const Correlation& a, const Correlation& b) {
  return (a.r - b.r).cwiseAbs().maxCoeff() / b.r.cwiseAbs().maxCoeff();
}

TEST(Correlators, DirectMatchesTheWrittenOutEstimator) {
  const Eigen::VectorXd u = white(60, 11), y = white(60, 12);
  for (int skip : {1, 2, 5}) {
    for (Eigen::Index z : {0, 3, 8}) {
      CorrelatorOptions o{.lags = 9, .zero_index = z, .skip = skip};
      const Correlation c = cross_correlation(y, u, o);
      ASSERT_EQ(c.zero_index, z);
      const Eigen::Index p = o.lags - 1 - z;
      for (Eigen::Index i = 0; i < o.lags; ++i) {
        const double expected = test::naive_lag(y, u, i - z, p, u.size() - 1 - z, skip);
        EXPECT_NEAR(c.r[i], expected, 1e-14) << "skip " << skip << " z " << z << " i " << i;
      }
    }
  }
}

TEST(Correlators, FftEqualsDirectWithin1e10) {
  const Eigen::VectorXd u = white(5000, 21);
  const Eigen::VectorXd y = fir(Eigen::Vector4d(0.0, 0.5, 1.0, -0.3), u) + 0.2 * white(5000, 22);
  for (int skip : {1, 3, 8}) {
    for (Eigen::Index z : {Eigen::Index{-1}, Eigen::Index{0}, Eigen::Index{255}}) {
      CorrelatorOptions o{.lags = 256, .zero_index = z, .skip = skip};
      const Correlation direct = cross_correlation(y, u, o);
      o.kind = CorrelatorKind::kFft;
      const Correlation fft = cross_correlation(y, u, o);
      EXPECT_LT(max_rel_diff(fft, direct), 1e-10) << "skip " << skip << " z " << z;
      EXPECT_LT(max_rel_diff(auto_correlation(u, o),
                             auto_correlation(u, {.lags = 256, .zero_index = z, .skip = skip})),
                1e-10);
    }
  }
}

// FFT plans are made under rig::signal::fftw_planner_mutex(), so concurrent use is safe.
TEST(Correlators, FftCorrelatorIsThreadSafe) {
  const Eigen::VectorXd u = white(3000, 25), y = white(3000, 26);
  const CorrelatorOptions o{.lags = 128, .kind = CorrelatorKind::kFft};
  const Correlation reference = cross_correlation(y, u, {.lags = 128});
  std::vector<double> worst(2, 0.0);
  std::vector<std::thread> threads;
  for (size_t k = 0; k < worst.size(); ++k) {
    threads.emplace_back([&, k] {
      for (int rep = 0; rep < 50; ++rep) {
        worst[k] = std::max(worst[k], max_rel_diff(cross_correlation(y, u, o), reference));
      }
    });
  }
  for (auto& t : threads) t.join();
  for (double w : worst) EXPECT_LT(w, 1e-10);
}

// y(t) = u(t - d): r_yu(tau) = E[u(t-d) u(t-tau)] peaks at tau = d, wherever lag 0 sits.
TEST(Correlators, DelayPeakLandsAtItsLagForEveryZeroIndex) {
  const Eigen::VectorXd u = white(4000, 31);
  const Eigen::Index d = 7;
  Eigen::VectorXd h = Eigen::VectorXd::Zero(d + 1);
  h[d] = 1.0;
  const Eigen::VectorXd y = fir(h, u);
  for (Eigen::Index z : {Eigen::Index{0}, Eigen::Index{10}, Eigen::Index{40}}) {
    const Correlation c = cross_correlation(y, u, {.lags = 64, .zero_index = z, .dt_s = 0.02});
    Eigen::Index peak = 0;
    c.r.maxCoeff(&peak);
    EXPECT_EQ(peak, z + d);
    EXPECT_DOUBLE_EQ(c.lag_s(peak), 0.02 * d);
  }
  const Correlation automatic = auto_correlation(u, {.lags = 256});
  EXPECT_EQ(automatic.zero_index, 102);  // floor(0.4 * 256)
  Eigen::Index peak = 0;
  automatic.r.maxCoeff(&peak);
  EXPECT_EQ(peak, 102);
}

// Bussgang: for Gaussian u, E[y sgn(u_{t-k})] = sqrt(2/pi) r_yu(k) / sigma_u. With white unit
// u and y = h * u (sum h^2 = 1), r_yu(k) = h_k and every product has variance <= E[y^2] = 1;
// products are (len h)-dependent, so 6/sqrt(N') is a bound of about 5 standard errors.
TEST(Correlators, RelayFollowsBussgang) {
  const Eigen::Index n = 400000;
  const double sigma_u = 2.0;
  const Eigen::VectorXd u = sigma_u * white(n, 41);
  Eigen::VectorXd h(4);
  h << 0.0, 0.8, 0.5, -0.33166247903554;  // unit norm
  const Eigen::VectorXd y = fir(h, u) / sigma_u;
  CorrelatorOptions o{.lags = 16, .zero_index = 4, .kind = CorrelatorKind::kRelay};
  const Correlation relay = cross_correlation(y, u, o);
  const double tol = 6.0 / std::sqrt(static_cast<double>(products_per_lag(o, n)));
  for (Eigen::Index i = 0; i < o.lags; ++i) {
    const Eigen::Index k = i - o.zero_index;
    const double r_true = (k >= 0 && k < h.size()) ? h[k] * sigma_u : 0.0;
    EXPECT_NEAR(relay.r[i], std::sqrt(2.0 / std::numbers::pi) * r_true / sigma_u, tol)
        << "lag " << k;
  }
}

// The relay scale sqrt(2/pi)/sigma_u is common to the auto and cross estimates: it cancels.
TEST(Correlators, RelayScaleCancelsBetweenAutoAndCross) {
  const Eigen::VectorXd u = white(3000, 51);
  const Eigen::VectorXd y = 2.5 * u;
  CorrelatorOptions o{.lags = 32, .kind = CorrelatorKind::kRelay};
  const Correlation ruu = auto_correlation(u, o), ryu = cross_correlation(y, u, o);
  EXPECT_LT((ryu.r - 2.5 * ruu.r).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(ruu.r[ruu.zero_index], 0.7);  // E|u| = sqrt(2/pi) = 0.80 for unit u
}

// Polarity: r_p = (2/pi) asin(rho) for jointly Gaussian signals; each product is +-1, so the
// standard error is <= 1/sqrt(N') and 5/sqrt(N') is a 5-sigma bound (pi/2 times that after
// the arcsine correction, whose slope is at most pi/2).
TEST(Correlators, PolarityFollowsTheArcsineLaw) {
  const Eigen::Index n = 200000;
  const Eigen::VectorXd u = white(n, 61), v = white(n, 62);
  for (double rho : {0.3, 0.7, 0.95}) {
    const Eigen::VectorXd y = rho * u + std::sqrt(1.0 - rho * rho) * v;
    CorrelatorOptions o{.lags = 5, .zero_index = 2, .kind = CorrelatorKind::kPolarity};
    const double tol = 5.0 / std::sqrt(static_cast<double>(products_per_lag(o, n)));
    const Correlation raw = cross_correlation(y, u, o);
    EXPECT_NEAR(raw.r[2], 2.0 / std::numbers::pi * std::asin(rho), tol) << "rho " << rho;
    EXPECT_GT(std::abs(raw.r[2] - rho), 3.0 * tol) << "the law is not the identity";
    o.arcsine_correction = true;
    const Correlation corrected = cross_correlation(y, u, o);
    EXPECT_NEAR(corrected.r[2], rho, std::numbers::pi / 2.0 * tol) << "rho " << rho;
    EXPECT_NEAR(corrected.r[0], 0.0, std::numbers::pi / 2.0 * tol);
  }
}

// Fell's skip forms a subset of the products, so E[r] is unchanged; only the variance grows.
// 300 seeded records; the mean over records must sit within 5 standard errors of h_k.
TEST(Correlators, SkipIsUnbiasedAndOnlyAddsVariance) {
  const int records = 300;
  const Eigen::Index n = 2048, lags = 24, z = 4;
  Eigen::VectorXd h(3);
  h << 0.6, 0.8, 0.0;
  std::cout << "[seed] records use seeds 1000.." << 1000 + records - 1 << "\n";
  for (int skip : {1, 8, 16}) {
    Eigen::MatrixXd est(lags, records);
    for (int rec = 0; rec < records; ++rec) {
      Xoshiro256 rng(1000 + rec);
      Eigen::VectorXd u(n);
      for (auto& x : u) x = rng.normal();
      est.col(rec) =
          cross_correlation(fir(h, u), u, {.lags = lags, .zero_index = z, .skip = skip}).r;
    }
    const Eigen::VectorXd mean = est.rowwise().mean();
    const Eigen::VectorXd sd =
        ((est.colwise() - mean).array().square().rowwise().sum() / (records - 1)).sqrt();
    for (Eigen::Index i = 0; i < lags; ++i) {
      const Eigen::Index k = i - z;
      const double truth = (k >= 0 && k < h.size()) ? h[k] : 0.0;
      EXPECT_NEAR(mean[i], truth, 5.0 * sd[i] / std::sqrt(records))
          << "skip " << skip << " lag " << k;
    }
    // Variance scales like 1/N' = skip/(n - lags + 1) for these nearly independent products.
    const double expected_sd = std::sqrt(skip / static_cast<double>(n - lags + 1));
    EXPECT_NEAR(sd.mean(), expected_sd, 0.25 * expected_sd) << "skip " << skip;
  }
}

// Fell's argument (thesis 3-2-4, Table 5-1): for an excitation band-limited to B, products
// closer than 1/(2B) are strongly correlated, so skipping them costs little variance while
// the slow rate 1/(s dt) stays above 2B, and variance grows ~ s beyond. Here B = 4 Hz at
// 100 Hz: s = 8 keeps the slow rate (12.5 Hz) above 2B, s = 64 (1.6 Hz) does not. 200 seeded
// records estimate each variance to ~10 %, so the thresholds (1.6x and 3x) have wide margins.
TEST(Correlators, SkipCostsLittleWhileTheSlowRateStaysAboveNyquist) {
  const int records = 200;
  const Eigen::Index n = 8192, lags = 32;
  std::cout << "[seed] gaussian excitation seeds 500.." << 500 + records - 1 << "\n";
  std::vector<Eigen::MatrixXd> est(3, Eigen::MatrixXd(lags, records));
  const int skips[] = {1, 8, 64};
  for (int rec = 0; rec < records; ++rec) {
    const Eigen::VectorXd u = gaussian_excitation(
        {.n = n, .dt_s = 0.01, .bandwidth_hz = 4.0, .seed = static_cast<std::uint64_t>(500 + rec)});
    const Eigen::VectorXd y = fir(Eigen::Vector4d(0.0, 0.2, 0.5, 0.3), u);
    for (int i = 0; i < 3; ++i) {
      est[i].col(rec) = cross_correlation(y, u, {.lags = lags, .skip = skips[i]}).r;
    }
  }
  std::vector<double> var(3);
  for (int i = 0; i < 3; ++i) {
    const Eigen::VectorXd mean = est[i].rowwise().mean();
    var[i] = (est[i].colwise() - mean).array().square().mean();
  }
  std::cout << "variance ratio to skip 1: skip 8 " << var[1] / var[0] << ", skip 64 "
            << var[2] / var[0] << "\n";
  EXPECT_LT(var[1] / var[0], 1.6);
  EXPECT_GT(var[2] / var[0], 3.0);
}

TEST(Correlators, BadArgumentsNameTheProblem) {
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(100);
  using ::testing::HasSubstr;
  auto message = [&](const CorrelatorOptions& o, const Eigen::VectorXd& y) -> std::string {
    try {
      cross_correlation(y, u, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_THAT(message({.lags = 101}, u), HasSubstr("lags (101) exceed the record length (100"));
  EXPECT_THAT(message({.lags = 10, .skip = 0}, u), HasSubstr("skip must be >= 1"));
  EXPECT_THAT(message({.lags = 0}, u), HasSubstr("lags must be >= 1"));
  EXPECT_THAT(message({.lags = 10, .zero_index = 10}, u), HasSubstr("zero_index"));
  EXPECT_THAT(message({.lags = 10, .dt_s = 0.0}, u), HasSubstr("dt_s"));
  EXPECT_THAT(message({.lags = 10, .arcsine_correction = true}, u),
              HasSubstr("arcsine_correction applies to kPolarity only"));
  EXPECT_THAT(message({.lags = 10}, Eigen::VectorXd::Ones(99)), HasSubstr("equally long"));
  EXPECT_EQ(cross_correlation(u, u, {.lags = 100}).size(), 100);  // one anchor is enough
}

}  // namespace
}  // namespace rig::signal
