// The residual tests of MATLAB `resid` (Ljung, System Identification, 2nd ed., 16.6):
//   whiteness  rho_rr(k) = sum r_t r_{t-k} / sum r_t^2, 99 % bound 2.58 / sqrt(N);
//   independence of past inputs  rho_ru(k) = sum r_t u_{t-k} / sqrt(sum r^2 sum u^2),
//   99 % bound 2.58 sqrt(P / N) with P = sum_{|tau| <= M} rho_rr(tau) rho_uu(tau).
// An output-error model is judged by the second: residual correlated with the input means
// unmodelled dynamics; a coloured residual uncorrelated with u is a disturbance. Over 2M+1
// lags the family-wise 1 % threshold is z = Phi^-1(1 - 0.005 / (2M+1)), i.e. the per-lag
// ratio to the 99 % bound must stay below z / 2.58.
#include "rig/ident/residual_tests.hpp"

#include <algorithm>
#include <cmath>

namespace rig::ident {
namespace {

// Phi^-1(p) for p in (0.5, 1) by bisection on erfc (accurate enough for a threshold).
double normal_quantile(double p) {
  double lo = 0.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > 1.0 - p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double lag_product(const Eigen::VectorXd& a, const Eigen::VectorXd& b, Eigen::Index k) {
  // sum_t a_t b_{t-k}
  const Eigen::Index n = a.size();
  if (k >= 0) return a.tail(n - k).dot(b.head(n - k));
  return a.head(n + k).dot(b.tail(n + k));
}

}  // namespace

ResidualTests residual_tests(const Eigen::VectorXd& r_in, const Eigen::VectorXd& u_in, double dt_s,
                             Eigen::Index max_lag, double family) {
  ResidualTests t;
  const Eigen::VectorXd r = r_in.array() - r_in.mean();
  const Eigen::VectorXd u = u_in.array() - u_in.mean();
  const Eigen::Index n = r.size();
  const Eigen::Index m = std::clamp<Eigen::Index>(max_lag, 1, std::max<Eigen::Index>(1, n / 4));
  const double rr = std::max(r.squaredNorm(), 1e-300), uu = std::max(u.squaredNorm(), 1e-300);
  t.auto_corr.resize(m + 1);
  Eigen::VectorXd ruu(m + 1);
  for (Eigen::Index k = 0; k <= m; ++k) {
    t.auto_corr(k) = lag_product(r, r, k) / rr;
    ruu(k) = lag_product(u, u, k) / uu;
  }
  double p = 1.0;
  for (Eigen::Index k = 1; k <= m; ++k) p += 2.0 * t.auto_corr(k) * ruu(k);
  const double sn = std::sqrt(static_cast<double>(n));
  t.auto_bound = 2.58 / sn;
  t.lags_s =
      Eigen::VectorXd::LinSpaced(2 * m + 1, static_cast<double>(-m), static_cast<double>(m)) * dt_s;
  t.cross_corr.resize(2 * m + 1);
  t.cross_bound = Eigen::VectorXd::Constant(2 * m + 1, 2.58 * std::sqrt(std::max(p, 1e-6)) / sn);
  for (Eigen::Index k = -m; k <= m; ++k)
    t.cross_corr(k + m) = lag_product(r, u, k) / std::sqrt(rr * uu);
  t.whiteness_ratio = t.auto_corr.tail(m).cwiseAbs().maxCoeff() / t.auto_bound;
  Eigen::Index at = 0;
  t.cross_ratio = (t.cross_corr.cwiseAbs().array() / t.cross_bound.array()).maxCoeff(&at);
  t.cross_peak_lag_s = t.lags_s(at);
  t.cross_threshold =
      normal_quantile(1.0 - 0.005 / (std::max(family, 1.0) * static_cast<double>(2 * m + 1))) /
      2.58;
  t.white = t.whiteness_ratio <= 1.0;
  t.independent = t.cross_ratio <= t.cross_threshold;
  return t;
}

}  // namespace rig::ident
