// An effect on the error of the governor's loop (placement.hpp, "error"): a memoryless
// nonlinearity N or a dead time.
//
// Knowing only the closed loop G (bias -> output) of a loop that tracks the bias with unity
// feedback (e = u - y / G0 drives the governor, so G' = G / G0 -> 1 at DC), the loop gain is
// L = G' / (1 - G'). A nonlinearity N on the error, y = G0 L N(e), is then the same as
//   y = G (u - d),  d = e - N(e),  e = u - y / G0,
// which needs no L: the baseline output z0 = G u less G d, stepped sample by sample because
// d depends on the output at the same instant. For N the identity, d = 0 and y = z0 exactly.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <span>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/governor_loop.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {

// z0 = simulate(tf, u); g0 = the loop's static gain (y per unit of e); on_error = N, given the
// error so far (its last element the current sample: a dead time reads the past ones).
// The correction G d is stepped with the first-order hold of model::simulate (exact for a
// whole-sample dead time; a fractional one is interpolated between samples, not split at
// its knot).
// With `feedback` the governor sees h(y / G0) instead of y / G0 (governor_loop.hpp: the
// governor_error and governor_pi places): e = u - h(y / G0). The linear loop is still G for
// any h (y = G u - G d holds whatever the loop's feedback), so N the identity gives z0.
Eigen::VectorXd close_error_loop(const model::TransferFunction& tf, const Eigen::VectorXd& u,
                                 const Eigen::VectorXd& z0, double g0, double dt_s,
                                 const std::function<double(std::span<const double>)>& on_error,
                                 const LoopFeedback* feedback = nullptr);

// The governor before a nonlinearity in its loop: a PI and its output filter,
// C = (1 + 1/(s T_i)) / (1 + s T_f), stepped as x_k = e_k + (dt/T_i) sum_{j<=k} e_j,
// f_k = p f_{k-1} + (1 - p) x_k, p = exp(-dt/T_f) (pi_filter_pole).
struct PiGovernor {
  double integral_time_s = 1.0;
  double filter_lag_s = 0.0;
};
double pi_filter_pole(double filter_lag_s, double dt_s);

// N for close_error_loop when the nonlinearity sits after the governor (placement.hpp,
// pi_loop): a_k = k f_k, its output through `step` (the effect's stepped form, state kept
// between samples), and the error that would have moved the governor's output as N did,
// e_k - d_k with C d = (a - N(a)) / k solved sample by sample (the filter and the PI
// inverted exactly in discrete time). A call for the sample already being solved
// (close_error_loop's passes) starts again from the state the previous sample left.
using Stepper = std::function<double(StepState& state, double x)>;
std::function<double(std::span<const double>)> pi_loop_on_error(Stepper step, double k,
                                                                const PiGovernor& governor,
                                                                double dt_s);

}  // namespace rig::diagnose
