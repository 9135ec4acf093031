// Estimated parameters with standard errors, and the figures derived from them.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "rig/model/transfer_function.hpp"

namespace rig::ident {

struct ParameterEstimate {
  std::string name;  // "a2", "a1", "a0", "b0", ... (index = power of s), "delay_s"
  double value = 0.0;
  double std_error = 0.0;  // NaN when unknown
};

// How the scale ambiguity of A(p) y = B(p) u is removed.
enum class Normalisation {
  kMonicDen,  // a_n = 1 (default: a_n never vanishes for an order-n model)
  kUnitB0,    // b_0 = 1 (the thesis' form 1 / (q2 s^2 + q1 s + q0))
};
const char* to_string(Normalisation normalisation);

// Second-order figures: static gain K = b0/a0, natural frequency wn = sqrt(a0/a2),
// damping ratio zeta = a1 / (2 sqrt(a0 a2)). Valid when n == 2.
struct DerivedFigures {
  bool valid = false;
  double gain = 0.0, gain_std = 0.0;
  double fn_hz = 0.0, fn_hz_std = 0.0;
  double zeta = 0.0, zeta_std = 0.0;
};

// Parameter vector layout used throughout: theta = [a_n ... a_0, b_m ... b_0].
Eigen::VectorXd pack_parameters(const model::TransferFunction& tf);
model::TransferFunction unpack_parameters(const Eigen::VectorXd& theta, model::ModelOrder order,
                                          double delay_s);
std::vector<std::string> parameter_names(model::ModelOrder order);

// tf rescaled to the given normalisation; the covariance of theta (layout above) is
// transformed consistently when cov is non-null (first-order propagation).
model::TransferFunction normalise(const model::TransferFunction& tf, Normalisation normalisation,
                                  Eigen::MatrixXd* cov = nullptr);

// Parameter table from a normalised TF and the covariance of theta (may be empty: std
// errors become NaN), with a final "delay_s" row.
std::vector<ParameterEstimate> parameter_table(const model::TransferFunction& tf,
                                               const Eigen::MatrixXd& cov, double delay_std_s);

// Second-order figures with standard errors by first-order (delta-method) propagation of
// cov (layout above; empty cov gives NaN std errors).
DerivedFigures derived_figures(const model::TransferFunction& tf, const Eigen::MatrixXd& cov);

}  // namespace rig::ident
