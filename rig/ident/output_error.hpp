// Time-domain output-error refinement: minimises |y - G(p) u|^2 over the coefficients of
// the monic model (and its dead time) by Levenberg-Marquardt from a start model (the MMFM
// estimate). The estimate the asymptotic covariance of frf_uncertainty.hpp describes with
// the weight Phi_u: consistent with coloured noise in open loop, and efficient when the noise
// is white (Ljung, 2nd ed., section 9.6).
#pragma once

#include <Eigen/Core>

#include "rig/model/transfer_function.hpp"

namespace rig::ident {

struct OutputErrorFit {
  model::TransferFunction model;  // monic
  double cost = 0.0;              // mean square residual
  int iterations = 0;
  bool improved = false;  // the start was improved (else model == model::monic(start))
};

// Throws std::invalid_argument for unequal lengths or an improper start. A start that is
// unstable is returned unchanged (improved = false).
// starts: several records joined end to end (model::RecordStarts; empty: one record).
OutputErrorFit refine_output_error(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                                   const model::TransferFunction& start, bool delay_free,
                                   const model::RecordStarts& starts = {});

}  // namespace rig::ident
