// Correlation-domain output-error refinement of an MMFM estimate.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>

#include "rig/ident/mmfm.hpp"
#include "rig/ident/srivc.hpp"

namespace rig::ident {
namespace {

model::TransferFunction from_theta(const Eigen::VectorXd& th, int n, int m, double delay_s) {
  model::TransferFunction tf;
  tf.den.resize(n + 1);
  tf.den << 1.0, th.head(n);
  tf.num = th.segment(n, m + 1);
  tf.delay_s = delay_s;
  return tf;
}

// Residual with the best initial-state transient removed (see model_cross_correlation).
double sse_of(const model::TransferFunction& tf, const signal::Correlation& ruu,
              const signal::Correlation& ryu) {
  if (!tf.is_stable() || tf.delay_s < 0.0) return std::numeric_limits<double>::infinity();
  const double v = (ryu.r - model_cross_correlation(tf, ruu, ryu).r).squaredNorm();
  return std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
}

// Orthonormal basis Q of the free responses of tf; x - Q Q^T x projects the initial-state
// transient out (variable projection, the basis' own dependence on theta neglected).
Eigen::MatrixXd transient_basis(const model::TransferFunction& tf, Eigen::Index samples,
                                double dt_s) {
  const Eigen::MatrixXd basis = model::free_response_basis(tf, samples, dt_s);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(basis);
  return qr.householderQ() * Eigen::MatrixXd::Identity(samples, basis.cols());
}

Eigen::MatrixXd project_out(const Eigen::MatrixXd& q, const Eigen::MatrixXd& x) {
  return x - q * (q.transpose() * x);
}

}  // namespace

MmfmResult refine_correlation_output_error(const signal::Correlation& ruu,
                                           const signal::Correlation& ryu, const MmfmResult& start,
                                           bool delay_free) {
  const model::TransferFunction m0 = model::monic(start.model);
  const int n = m0.order(), m = static_cast<int>(m0.num.size()) - 1;
  const Eigen::Index p = n + m + 1 + (delay_free ? 1 : 0);
  Eigen::VectorXd th(n + m + 2);
  th << m0.den.tail(n), m0.num, m0.delay_s;
  double v = sse_of(m0, ruu, ryu), lambda = 1e-3;
  if (!std::isfinite(v)) return start;
  Eigen::MatrixXd jtj;
  for (int it = 0; it < 50; ++it) {
    const model::TransferFunction tf = from_theta(th, n, m, th(n + m + 1));
    const Eigen::MatrixXd q = transient_basis(tf, ryu.size(), ryu.dt_s);
    const Eigen::VectorXd e = project_out(q, ryu.r - simulate(tf, ruu.r, ruu.dt_s));
    const Eigen::MatrixXd j = project_out(q, output_sensitivities(tf, ruu.r, ruu.dt_s).leftCols(p));
    jtj = j.transpose() * j;
    const Eigen::VectorXd g = j.transpose() * e;
    bool accepted = false;
    for (int tries = 0; tries < 12 && !accepted; ++tries) {
      Eigen::MatrixXd a = jtj;
      a.diagonal() += lambda * jtj.diagonal();
      Eigen::VectorXd step = Eigen::VectorXd::Zero(th.size());
      step.head(p) = a.ldlt().solve(g);
      const Eigen::VectorXd cand = th + step;
      const double vc = sse_of(from_theta(cand, n, m, cand(n + m + 1)), ruu, ryu);
      if (vc < v) {
        accepted = true;
        const double rel = (v - vc) / v;
        th = cand, v = vc, lambda = std::max(1e-9, lambda / 3.0);
        if (rel < 1e-12) it = 1000;
      } else {
        lambda *= 4.0;
      }
    }
    if (!accepted) break;
  }
  MmfmResult res = start;
  const model::TransferFunction tf = from_theta(th, n, m, th(n + m + 1));
  const Eigen::MatrixXd j = project_out(transient_basis(tf, ryu.size(), ryu.dt_s),
                                        output_sensitivities(tf, ruu.r, ruu.dt_s).leftCols(p));
  const double s2 = v / std::max<double>(1.0, static_cast<double>(ryu.size() - p));
  const Eigen::MatrixXd cov_p = s2 * (j.transpose() * j).inverse();
  // Covariance on theta = [a_n..a_0, b_m..b_0] (a_n = 1 fixed), then the caller's normalisation.
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(n + m + 2, n + m + 2);
  cov.bottomRightCorner(n + m + 1, n + m + 1) = cov_p.topLeftCorner(n + m + 1, n + m + 1);
  res.model = normalise(tf, start.settings.normalisation, &cov);
  res.covariance = cov;
  res.delay_s = tf.delay_s;
  if (delay_free) res.delay_std_s = std::sqrt(std::max(0.0, cov_p(p - 1, p - 1)));
  res.model_ryu = model_cross_correlation(res.model, ruu, ryu);
  res.correlation_fit_pct = model::fit_percent(ryu.r, res.model_ryu.r);
  res.derived = derived_figures(res.model, res.covariance);
  res.parameters = parameter_table(res.model, res.covariance, res.delay_std_s);
  res.refined = true;
  return res;
}

}  // namespace rig::ident
