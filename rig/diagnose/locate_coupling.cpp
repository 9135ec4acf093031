// The coupling test: an AC coupling of the output that the model lacks (an undeclared RC
// high-pass in the measurement chain) leaves y - yhat = -LP_RC(yhat) beside the noise, LP_RC
// the coupling's complement 1 / (RC s + 1). Its time scale is the drift test's: a coupling of
// RC 15 s sits below most of the excitation's band, where the frequency and cross-correlation
// tests see the output's own wander, and it is slow enough to pass for a drift.
//
// The residual is regressed on [1, LP_RC(yhat)] by generalised least squares for each RC of a
// grid; like the step-gain test, the test fires when the coefficient agrees with the -1 a
// coupling gives and that reading is much likelier than none.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/residual_stats.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {
namespace {

// x through 1 / (RC s + 1) by backward Euler, from rest.
Eigen::VectorXd low_pass(const Eigen::VectorXd& x, double rc_s, double dt_s) {
  Eigen::VectorXd y(x.size());
  const double a = dt_s / (rc_s + dt_s);
  double s = 0.0;
  for (Eigen::Index k = 0; k < x.size(); ++k) y(k) = s += a * (x(k) - s);
  return y;
}

}  // namespace

CouplingTest locate_coupling(const Problem& pr, const Eigen::VectorXd& r_all,
                             const Eigen::VectorXd& yh_all) {
  CouplingTest best;
  const Eigen::Index n = r_all.size();
  Eigen::Index from = 0;
  while (from < n && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::Index m = n - from;
  if (m < 256) return best;
  const Eigen::VectorXd dev = yh_all.array() - yh_all.tail(m).mean();
  const Eigen::VectorXd r = r_all.tail(m);
  const double rc_to_s = pr.scales.duration_s / thresholds::kCouplingRcsPerRecord;
  for (double rc_s = thresholds::kCouplingRcFromS; rc_s <= rc_to_s; rc_s *= std::sqrt(2.0)) {
    Eigen::MatrixXd x(m, 2);
    x.col(0).setOnes();
    x.col(1) = low_pass(dev, rc_s, pr.dt_s).tail(m);
    // The regressor is slower than the whitener's reach: its correlation with what colour
    // is left counts over three time constants.
    const auto lags = std::min<Eigen::Index>(m / 4, std::llround(3.0 * rc_s / pr.dt_s));
    const GlsFit gls = gls_fit(x, r, x.col(1), thresholds::kWhitenOrder, lags);
    CouplingTest t;
    t.tested = true;
    t.rc_s = rc_s;
    t.beta = gls.fit.beta(1);
    t.sd = std::sqrt(std::max(gls.s2 * gls.fit.inv(1, 1), 1e-300));
    const double z = t.beta / t.sd, z_coupled = (t.beta + 1.0) / t.sd;
    t.log_likelihood_ratio = 0.5 * (z * z - z_coupled * z_coupled);
    t.fires = t.beta < 0.0 && std::abs(z_coupled) <= thresholds::kStepGainAgreeSds &&
              t.log_likelihood_ratio >= std::log(thresholds::kCouplingLikelihoodRatio);
    if (!best.tested || t.log_likelihood_ratio > best.log_likelihood_ratio) best = t;
  }
  return best;
}

}  // namespace rig::diagnose
