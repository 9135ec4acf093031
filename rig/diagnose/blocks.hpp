// Elementary blocks the hypotheses are built from: memoryless and hysteretic input
// nonlinearities, polynomial operations on transfer functions, and a sample-by-sample
// simulation of a rational transfer function closed through an output nonlinearity.
#pragma once

#include <Eigen/Core>
#include <functional>

#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {

// Deadband of half-width w: v = u - w (u > w), u + w (u < -w), 0 in between.
Eigen::VectorXd deadband(const Eigen::VectorXd& u, double half_width);
// Backlash (play operator) of half-width b: v_k = min(max(v_{k-1}, u_k - b), u_k + b),
// starting engaged at v_0 = u_0.
Eigen::VectorXd backlash(const Eigen::VectorXd& u, double half_width);
// Bouc-Wen hysteresis (n = 1) as an input operator: v = u - z with
//   dz = du - beta |du| z - gamma du |z|,  beta = 1 / (w (1 + r)), gamma = r beta,
// so z saturates at +-w (a lag of w behind every sustained movement, like a play of
// half-width w) and the shape ratio r = gamma/beta in (-1, 1] sets how smoothly it engages
// (r = 1: a play whose return is linear at once; r near -1: a slow, rounded engagement).
// Rate-independent: each step applies the increment du_k = u_k - u_{k-1}; z_0 = 0.
Eigen::VectorXd bouc_wen(const Eigen::VectorXd& u, double half_width, double shape_ratio);
// One step of it: z after the increment du.
double bouc_wen_step(double z, double du, double half_width, double shape_ratio);
// Hard limits: v = min(max(u, lower), upper).
Eigen::VectorXd saturate(const Eigen::VectorXd& u, double lower, double upper);
// Rate limit r: v_k = v_{k-1} + clamp(u_k - v_{k-1}, -r dt, r dt), v_0 = u_0.
Eigen::VectorXd rate_limit(const Eigen::VectorXd& u, double rate_per_s, double dt_s);
// The same limits inside an integrating loop (a governor's integrator with anti-windup, whose
// droop or speed loop restores the lost position with the time constant T = recovery_s):
//   v_k = v_{k-1} + clamp(u_k - u_{k-1} + (u_{k-1} - v_{k-1}) dt/T, -r dt, r dt)   (rate)
//   v_k = min(max(v_{k-1} + u_k - u_{k-1} + (u_{k-1} - v_{k-1}) dt/T, lower), upper)
// T = dt gives the plain limiters above: the position is restored at once.
// The share of the lost position restored in one step, dt/T (at most all of it).
double in_loop_recovery(double recovery_s, double dt_s);
Eigen::VectorXd rate_limit_in_loop(const Eigen::VectorXd& u, double rate_per_s, double recovery_s,
                                   double dt_s);
Eigen::VectorXd saturate_in_loop(const Eigen::VectorXd& u, double lower, double upper,
                                 double recovery_s, double dt_s);
// Static polynomial about the operating point, coefficients relative to sigma = std(u):
//   v = u + c2 u^2 / sigma + c3 u^3 / sigma^2.
Eigen::VectorXd polynomial(const Eigen::VectorXd& u, double c2_rel, double c3_rel, double sigma);

// Polynomial product (coefficients highest power first).
Eigen::VectorXd poly_multiply(const Eigen::VectorXd& a, const Eigen::VectorXd& b);
// Real polynomial with the given roots (conjugates paired), leading coefficient 1.
Eigen::VectorXd poly_from_roots(const Eigen::VectorXcd& roots);

// Output feedback through a nonlinearity: v'_k = ud_k - f(z_k, dz_k), where ud is the input
// delayed by the tf's dead time, z = the rational part's output and dz its rate (backward
// difference). Discretised with a zero-order hold on the mid-sample input
// (ud_k + ud_{k+1}) / 2, which has no half-sample lag, so f = 0 reproduces simulate() to
// second order in dt.
using OutputFeedback = std::function<double(double z, double dz)>;
Eigen::VectorXd simulate_with_feedback(const model::TransferFunction& tf, const Eigen::VectorXd& u,
                                       double dt_s, const OutputFeedback& feedback);

// Zero-phase exponential smoother (forward then backward first-order low-pass, time
// constant tau each way): the drift estimate of a residual.
Eigen::VectorXd smooth_zero_phase(const Eigen::VectorXd& x, double tau_s, double dt_s);

}  // namespace rig::diagnose
