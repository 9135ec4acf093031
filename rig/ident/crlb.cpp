#include "rig/ident/crlb.hpp"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

#include "rig/ident/srivc.hpp"

namespace rig::ident {

CramerRaoBound cramer_rao_bound(const model::TransferFunction& true_tf, const Eigen::VectorXd& u,
                                double dt_s, double noise_variance, bool delay_known) {
  if (!(noise_variance > 0.0))
    throw std::invalid_argument("cramer_rao_bound: noise_variance must be > 0");
  const model::TransferFunction tf = model::monic(true_tf);
  const int n = tf.order(), m = static_cast<int>(tf.num.size()) - 1;
  const Eigen::MatrixXd jac = output_sensitivities(tf, u, dt_s);
  CramerRaoBound out;
  const Eigen::Index q = jac.cols() - (delay_known ? 1 : 0);
  const Eigen::MatrixXd info = jac.leftCols(q).transpose() * jac.leftCols(q);
  out.covariance = Eigen::MatrixXd::Zero(jac.cols(), jac.cols());
  out.covariance.topLeftCorner(q, q) = noise_variance * info.inverse();
  out.std_dev = out.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  const model::ModelOrder order{n, m};
  const std::vector<std::string> names = parameter_names(order);
  out.names.assign(names.begin() + 1, names.end());  // a_n = 1 is not a parameter
  out.names.push_back("delay_s");
  const Eigen::Index p = n + m + 2;
  Eigen::MatrixXd cov_full = Eigen::MatrixXd::Zero(p, p);
  cov_full.bottomRightCorner(p - 1, p - 1) = out.covariance.topLeftCorner(p - 1, p - 1);
  out.derived = derived_figures(tf, cov_full);
  return out;
}

}  // namespace rig::ident
