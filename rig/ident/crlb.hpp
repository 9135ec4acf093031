// Cramer-Rao lower bound for the output-error model y = H(p) u + v, v white N(0, sigma^2):
//     Fisher information F = J^T J / sigma^2,  J = d y_hat / d theta (noise-free, true tf)
// for theta = [a_{n-1}..a_0, b_m..b_0, Td] (monic denominator). Any unbiased estimator's
// covariance is at least F^{-1}; efficiency = CRLB variance / observed variance.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "rig/ident/parameters.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::ident {

struct CramerRaoBound {
  std::vector<std::string> names;  // a_{n-1}..a_0, b_m..b_0, delay_s
  Eigen::MatrixXd covariance;      // F^{-1}
  Eigen::VectorXd std_dev;         // sqrt(diag)
  DerivedFigures derived;          // second order: bounds on gain, fn, zeta (std fields)
};

// delay_known: Td is not estimated (its row and column are dropped; reported std 0).
CramerRaoBound cramer_rao_bound(const model::TransferFunction& true_tf, const Eigen::VectorXd& u,
                                double dt_s, double noise_variance, bool delay_known = false);

}  // namespace rig::ident
