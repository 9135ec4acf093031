// Simplified refined instrumental variable method for continuous-time transfer functions
// (SRIVC; Young, Garnier; as CONTSID srivc / MATLAB tfest), with dead time.
//
// With the current denominator A_hat, every signal is prefiltered by 1/A_hat(p) and the
// filtered derivatives p^i/A_hat y, p^j/A_hat u(t - Td) form the regression
//     p^n y_f = -sum_{i<n} a_i p^i y_f + sum_j b_j p^j u_f      (a_n = 1)
// whose instruments replace y by the auxiliary-model output x_hat = B_hat/A_hat u. Iterated
// to convergence from a state-variable-filter least-squares start. The dead time is found
// by a 1-D search on the output-error cost.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "rig/ident/parameters.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::ident {

struct SrivcOptions {
  model::ModelOrder order;
  std::optional<double> delay_s;  // nullopt: searched over [0, max_delay_s]
  double max_delay_s = 0.5;
  int max_iterations = 30;
  double tolerance = 1e-7;       // relative parameter change that ends the iteration
  double svf_cutoff_rad_s = -1;  // initial filter (p + lambda)^n; < 0: automatic
  // Several records joined end to end (model::RecordStarts; empty: one record): each is
  // filtered and simulated from zero state, and its filters' start-up is skipped.
  model::RecordStarts starts;
};

struct SrivcResult {
  model::TransferFunction model;              // monic denominator
  std::vector<ParameterEstimate> parameters;  // with std errors, last row delay_s
  Eigen::MatrixXd covariance;                 // of [a_{n-1}..a_0, b_m..b_0, Td]
  double delay_s = 0.0;
  double delay_std_s = 0.0;
  DerivedFigures derived;
  double noise_variance = 0.0;  // output-error residual variance
  double fit_pct = 0.0;         // output-error fit on the data used
  int iterations = 0;
  bool converged = false;
};

SrivcResult estimate_srivc(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                           const SrivcOptions& options);

// Output sensitivities d y_hat / d theta for theta = [a_{n-1}..a_0, b_m..b_0, Td] of the
// monic model tf driven by u (columns, N rows): the Jacobian of the output-error model.
Eigen::MatrixXd output_sensitivities(const model::TransferFunction& tf, const Eigen::VectorXd& u,
                                     double dt_s, const model::RecordStarts& starts = {});

}  // namespace rig::ident
