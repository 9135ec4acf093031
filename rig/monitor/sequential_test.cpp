#include "rig/monitor/sequential_test.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rig::monitor {
namespace {

// Upper 95 % factor for a standard deviation from n values: sqrt((n - 1) / chi2_{0.05, n-1}),
// with the Wilson-Hilferty approximation of the chi-square quantile.
double sigma_upper_factor(int n) {
  const double nu = n - 1;
  const double z = -1.6449;  // 5 % lower quantile of N(0,1)
  const double c = 2.0 / (9.0 * nu);
  const double q = nu * std::pow(1.0 - c + z * std::sqrt(c), 3.0);
  return std::sqrt(nu / std::max(q, 1e-9));
}

}  // namespace

Spread learn_spread(const std::vector<double>& v) {
  Spread s;
  s.n = static_cast<int>(v.size());
  if (s.n < 3) {
    s.sigma = s.raw_sigma = std::numeric_limits<double>::infinity();
    return s;
  }
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean = sum / s.n;
  double ss = 0.0, lag = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    ss += (v[i] - s.mean) * (v[i] - s.mean);
    if (i > 0) lag += (v[i] - s.mean) * (v[i - 1] - s.mean);
  }
  s.raw_sigma = std::sqrt(ss / (s.n - 1));
  s.rho = ss > 0.0 ? std::clamp(lag / ss, 0.0, 0.9) : 0.0;
  s.sigma = s.raw_sigma * std::sqrt((1.0 + s.rho) / (1.0 - s.rho)) * sigma_upper_factor(s.n);
  return s;
}

double cusum_arl0(double k, double h) {
  const double b = h + 1.166;
  return (std::exp(2.0 * k * b) - 2.0 * k * b - 1.0) / (2.0 * k * k);
}

double cusum_arl1(double k, double h, double d) {
  const double delta = d - k;
  const double b = h + 1.166;
  if (std::abs(delta) < 1e-9) return b * b;
  return (std::exp(-2.0 * delta * b) + 2.0 * delta * b - 1.0) / (2.0 * delta * delta);
}

CusumDesign design_cusum(double false_alarms_per_month, double block_s, int tests, double k) {
  CusumDesign d;
  d.k = k;
  const double blocks_per_month = kMonthS / block_s;
  // Two one-sided sums per test: total rate 2 tests / ARL0 per block.
  const double needed = 2.0 * tests * blocks_per_month / std::max(false_alarms_per_month, 1e-9);
  double h = 0.5;
  while (cusum_arl0(k, h) < needed && h < 200.0) h += 0.01;
  d.h = h;
  d.arl0_blocks = cusum_arl0(k, h) / 2.0;
  d.false_alarms_per_month = 2.0 * tests * blocks_per_month / cusum_arl0(k, h);
  return d;
}

int Cusum::update(double z) {
  if (!std::isfinite(z)) return 0;
  up_ = std::max(0.0, up_ + z - d_.k);
  down_ = std::max(0.0, down_ - z - d_.k);
  up_run_ = up_ > 0.0 ? up_run_ + 1 : 0;
  down_run_ = down_ > 0.0 ? down_run_ + 1 : 0;
  run_ = up_ > down_ ? up_run_ : down_run_;
  if (up_ > d_.h) {
    up_ = down_ = 0.0;
    return +1;
  }
  if (down_ > d_.h) {
    up_ = down_ = 0.0;
    return -1;
  }
  return 0;
}

}  // namespace rig::monitor
