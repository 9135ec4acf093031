#include "rig/ident/output_error.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rig/ident/srivc.hpp"

namespace rig::ident {
namespace {

constexpr int kMaxIterations = 30;
constexpr int kMaxDampingTries = 10;
constexpr double kRelativeStop = 1e-9;  // relative cost decrease that ends the iteration

model::TransferFunction from_theta(const Eigen::VectorXd& th, int n, int m) {
  model::TransferFunction tf;
  tf.den.resize(n + 1);
  tf.den << 1.0, th.head(n);
  tf.num = th.segment(n, m + 1);
  tf.delay_s = th(n + m + 1);
  return tf;
}

double cost_of(const model::TransferFunction& tf, const Eigen::VectorXd& u,
               const Eigen::VectorXd& y, double dt_s, const model::RecordStarts& starts) {
  if (!tf.is_stable() || tf.delay_s < 0.0) return std::numeric_limits<double>::infinity();
  const double v =
      (y - model::simulate(tf, u, dt_s, starts)).squaredNorm() / static_cast<double>(y.size());
  return std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
}

}  // namespace

OutputErrorFit refine_output_error(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                                   const model::TransferFunction& start, bool delay_free,
                                   const model::RecordStarts& starts) {
  if (u.size() != y.size())
    throw std::invalid_argument("refine_output_error: u and y lengths differ");
  if (!start.is_proper()) throw std::invalid_argument("refine_output_error: improper start model");
  const model::TransferFunction m0 = model::monic(start);
  const int n = m0.order(), m = static_cast<int>(m0.num.size()) - 1;
  const Eigen::Index p = n + m + 1 + (delay_free ? 1 : 0);
  Eigen::VectorXd th(n + m + 2);
  th << m0.den.tail(n), m0.num, m0.delay_s;
  OutputErrorFit fit;
  fit.model = m0;
  double v = cost_of(m0, u, y, dt_s, starts), lambda = 1e-3;
  fit.cost = v;
  if (!std::isfinite(v)) return fit;
  for (int it = 0; it < kMaxIterations; ++it) {
    const model::TransferFunction tf = from_theta(th, n, m);
    const Eigen::VectorXd e = y - model::simulate(tf, u, dt_s, starts);
    const Eigen::MatrixXd j = output_sensitivities(tf, u, dt_s, starts).leftCols(p);
    const Eigen::MatrixXd jtj = j.transpose() * j;
    const Eigen::VectorXd g = j.transpose() * e;
    bool accepted = false;
    for (int tries = 0; tries < kMaxDampingTries && !accepted; ++tries) {
      Eigen::MatrixXd a = jtj;
      a.diagonal() += lambda * jtj.diagonal();
      Eigen::VectorXd cand = th;
      cand.head(p) += a.ldlt().solve(g);
      const double vc = cost_of(from_theta(cand, n, m), u, y, dt_s, starts);
      if (vc < v) {
        accepted = true;
        const double rel = (v - vc) / v;
        th = cand, v = vc, lambda = std::max(1e-9, lambda / 3.0);
        fit.improved = true;
        if (rel < kRelativeStop) it = kMaxIterations;
      } else {
        lambda *= 4.0;
      }
    }
    fit.iterations = it + 1;
    if (!accepted) break;
  }
  fit.model = from_theta(th, n, m);
  fit.cost = v;
  return fit;
}

}  // namespace rig::ident
