// Statistics the location's time and amplitude tests share (locate_time.cpp,
// locate_amplitude.cpp): least squares on the used rows, the Bartlett factor of two
// correlated series, the drift-free baseline response to a masked input, a span of rows.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "rig/diagnose/augmented_model.hpp"

namespace rig::diagnose {

// The q-quantile of v (0 for none).
double quantile(std::vector<double> v, double q);

// 1 + 2 sum_k rho_a(k) rho_b(k) over k = 1..max_lag on the used samples: N / N_eff of a
// regression of a on b when both are coloured.
double bartlett_factor(const Eigen::VectorXd& a, const Eigen::VectorXd& b, Eigen::Index lags);

// Least squares r = X beta on the used rows; returns beta, the residual sum of squares and
// (X'X)^-1.
struct Ls {
  Eigen::VectorXd beta;
  double rss = 0.0;
  Eigen::MatrixXd inv;
};
Ls least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& r);

// The whitening filter A(q) = 1 + a_1 q^-1 + ... + a_p q^-p of an AR(p) fitted to e by least
// squares (a = [1, a_1, ..., a_p]); [1] when e is too short or flat.
Eigen::VectorXd ar_whitener(const Eigen::VectorXd& e, int order);
// x filtered by A(q), its first p samples dropped (they have no full history).
Eigen::VectorXd whiten(const Eigen::VectorXd& x, const Eigen::VectorXd& a);

// Generalised least squares r = X beta: the first fit's residual gives an AR whitener of the
// given order (its colour: a drift, the grid's wander, a transducer's lag), r and X are
// whitened and fitted again. s2 is the whitened residual's variance per effective sample
// (the Bartlett factor over `lags` against `reference` whitened alike: about 1 once the
// colour is out, unless the regressor is slower than the whitener reaches), so s2 * fit.inv
// is beta's covariance.
struct GlsFit {
  Ls fit;
  double s2 = 0.0;
};
GlsFit gls_fit(const Eigen::MatrixXd& x, const Eigen::VectorXd& r, const Eigen::VectorXd& reference,
               int order, Eigen::Index lags);

// Slow content (below the drift test's time scale) removed: a drift must not project onto
// regressors that carry a mean, such as G(u 1{u >= 0}).
Eigen::VectorXd detrend(const Problem& pr, const Eigen::VectorXd& x);

// The baseline's response to u restricted by a mask (u outside the mask set to zero),
// detrended.
Eigen::VectorXd masked_response(const Problem& pr, const Eigen::VectorXd& u);

// The rows [from, to) (to < 0: the end) past the warm-up: r and yh detrended there, their
// Bartlett factor c and the effective number of samples m / c.
struct Rows {
  Eigen::Index from = 0, m = 0;
  Eigen::VectorXd r, yh;
  double c = 1.0, n_eff = 0.0;
  // x's rows of the span.
  Eigen::VectorXd of(const Eigen::VectorXd& x) const { return x.segment(from, m); }
};
// Nothing when fewer rows than an amplitude test needs (64).
std::optional<Rows> rows_of(const Problem& pr, const Eigen::VectorXd& r_all,
                            const Eigen::VectorXd& yh_all, Eigen::Index from, Eigen::Index to);

}  // namespace rig::diagnose
