// The residual tests of MATLAB `resid` (Ljung, System Identification, 2nd ed., 16.6), shared
// by `rig identify` (the validation record's residual) and `rig diagnose` (the baseline's).
#pragma once

#include <Eigen/Core>

namespace rig::ident {

struct ResidualTests {
  Eigen::VectorXd lags_s;        // -M..M (cross); the auto-correlation uses 0..M of them
  Eigen::VectorXd auto_corr;     // rho_rr(k), k = 0..M
  Eigen::VectorXd cross_corr;    // rho_ru(k), k = -M..M (residual now, input k earlier)
  Eigen::VectorXd cross_bound;   // 99 % bound per lag (Ljung 16.60)
  double auto_bound = 0.0;       // 2.58 / sqrt(N)
  double whiteness_ratio = 0.0;  // max |rho_rr(k>0)| / bound
  double cross_ratio = 0.0;      // max |rho_ru(k)| / bound_k
  double cross_peak_lag_s = 0.0;
  double cross_threshold = 0.0;  // family-wise (over lags) ratio threshold
  bool white = true, independent = true;
};

// residual and input of one record; max_lag M is clamped to [1, N/4]. family: how many such
// tests share the 1 % (Bonferroni: each half of a record, 2).
ResidualTests residual_tests(const Eigen::VectorXd& residual, const Eigen::VectorXd& u, double dt_s,
                             Eigen::Index max_lag, double family = 1.0);

}  // namespace rig::ident
