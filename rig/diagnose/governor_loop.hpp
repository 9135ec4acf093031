// A linear effect inside the governor's loop, the loop's feedback fitted (placement.hpp,
// "governor_loop").
//
// Knowing only the closed loop G (bias -> output, its dead time left outside the loop) and
// G' = G / G0, take G' as a loop with forward part P and feedback h:
//   G' = P / (1 + P h),  so  P = G' / (1 - G' h).
// A factor F (a lag, a transport delay) in the forward part makes the closed loop
//   G_new = G F / (1 - G' h (1 - F)),
// which is G again for F = 1 and keeps the static gain G0 (F(0) = 1). h is what the
// governor sees of the output: a static share (a power or load feedback) and a rate share
// (speed, the swing equation's derivative of power, as a droop governor sees it), filtered:
//   h = (a + b s T_h) / (1 + s T_h),  a = loop_static_share, b = loop_rate_share,
//                                     T_h = loop_filter_s.
// With h = 1 it is the unity loop of the `error` place (error_loop.hpp). As polynomials,
// with G = N / D, F = nf / df, h = nh / dh:
//   G_new = G0 N nf dh / (G0 D df dh - N nh (df - nf)).
#pragma once

#include <Eigen/Core>
#include <span>

#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {

// Whether tf can be closed that way: a finite, non-zero static gain.
bool governor_loop_possible(const model::TransferFunction& tf);

// G_new for the factor F = nf / df (highest power first, F(0) = 1) and the place's
// parameters (a, b, T_h); the dead time of tf is kept outside.
model::TransferFunction close_governor_loop(const model::TransferFunction& tf,
                                            const Eigen::VectorXd& nf, const Eigen::VectorXd& df,
                                            std::span<const double> place_params);

// The Pade approximant of order 3 of e^{-s tau} (a transport delay inside the loop), or 1
// for a delay under a microsecond.
void pade_delay(double tau_s, Eigen::VectorXd& num, Eigen::VectorXd& den);

}  // namespace rig::diagnose
