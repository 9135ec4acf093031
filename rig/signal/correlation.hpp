// A sampled two-sided correlation function, the currency between the correlators
// (rig/signal) and the estimators (rig/ident).
//
// Convention (MMFM.md section 2): r_yu(tau) = E[ y(t) u(t - tau) ], so a causal system's
// cross-correlation lives at tau >= 0 (output lags input). Sample i holds lag
// tau_i = (i - zero_index) * dt_s; lags run from -zero_index*dt_s to
// (size()-1-zero_index)*dt_s. The zero-lag position is a free choice (thesis 5-1-1: best
// 30-60 % into the window).
#pragma once

#include <Eigen/Core>

namespace rig::signal {

struct Correlation {
  Eigen::VectorXd r;            // values at each lag
  Eigen::Index zero_index = 0;  // index of lag 0 within r
  double dt_s = 0.0;            // lag resolution (the fast sample period)

  Eigen::Index size() const { return r.size(); }
  double lag_s(Eigen::Index i) const { return static_cast<double>(i - zero_index) * dt_s; }
  Eigen::Index negative_lags() const { return zero_index; }
  Eigen::Index positive_lags() const { return r.size() - 1 - zero_index; }
};

}  // namespace rig::signal
