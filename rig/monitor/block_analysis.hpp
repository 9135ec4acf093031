// One block of monitoring data against the baseline model (seed 002, section 3):
//
//   parity residual   r = y_c - G0(p) u_c   (output-error parity equation: the baseline model
//                     run on the AC-coupled excitation; the state-variable filter is the
//                     model's own simulation, warmed up on the samples before the block)
//   sensitivities     s_i = (G_i(p) u_c - G0(p) u_c) / probe_i for each tracked parameter
//                     (tracked_parameters.hpp): how the output moves per unit deviation
//   single fits       d_i = s_i'r / s_i's_i  and the residual energy each removes,
//                     (s_i'r)^2 / s_i's_i: the parameter that alone explains most of r is
//                     the one isolated as moved
//   joint fit         d = (S'S)^-1 S'r with its white-noise standard errors
//                     sigma_r sqrt(diag (S'S)^-1): the thresholds follow the excitation
//                     level (S grows with it) and the residual (the model's uncertainty)
//   line              the engine-order line at the cycle frequency (speed / 120 Hz for a
//                     four-stroke: a missing cylinder's half-order) in r, as the ratio of its
//                     power to the mean power of nearby frequencies (log10)
#pragma once

#include <Eigen/Core>
#include <vector>

#include "rig/model/transfer_function.hpp"

namespace rig::monitor {

struct BlockFit {
  int parameters = 0;
  Eigen::VectorXd joint;             // d, joint fit (deviation in the registry's raw units)
  Eigen::VectorXd joint_se;          // white-noise standard errors of d
  Eigen::VectorXd single;            // d_i, single-parameter fits
  Eigen::VectorXd explained;         // residual energy share each single fit removes (0..1)
  Eigen::MatrixXd normal;            // S'S (for exponentially forgotten tracking)
  Eigen::VectorXd rhs;               // S'r
  double residual_rms_kw = 0.0;      // of r
  double response_rms_kw = 0.0;      // of G0 u_c
  double fit_residual_rms_kw = 0.0;  // of r after the joint fit
  double line_log_ratio = 0.0;       // log10 line power / neighbourhood power (NaN: no speed)
  double line_hz = 0.0;
};

// u_c: coupled excitation, warm-up samples first, then the block; y_c: coupled response of
// the block only (its last y_c.size() samples align with u_c's last). models[0] is the
// baseline, models[i + 1] the deformed model for parameter i with probes[i].
BlockFit analyse_block(const std::vector<model::TransferFunction>& models,
                       const std::vector<double>& probes, const Eigen::VectorXd& u_c,
                       const Eigen::VectorXd& y_c, double dt_s, double speed_rpm);

// Power ratio of the line at f_hz in x to the mean of the bins at +-3..8 bin spacings,
// log10; NaN when f_hz is not inside (0, Nyquist).
double line_log_ratio(const Eigen::VectorXd& x, double dt_s, double f_hz);

}  // namespace rig::monitor
