// A linear effect inside the governor's loop, the loop's feedback fitted (placement.hpp,
// "governor_loop").
//
// Knowing only the closed loop G (bias -> output, its dead time left outside the loop) and
// G' = G / G0, take G' as a loop with forward part P and feedback h:
//   G' = P / (1 + P h),  so  P = G' / (1 - G' h).
// A factor F (a lag, a transport delay) in the forward part makes the closed loop
//   G_new = G F / (1 - G' h (1 - F)),
// which is G again for F = 1 and keeps the static gain G0 (F(0) = 1). h is what the
// governor sees of the output: a static share (a power or load feedback) and a derivative
// (speed, the swing equation's derivative of power, as a droop governor sees it), filtered:
//   h = (a + s T_d) / (1 + s T_h),  a = loop_static_share, T_d = loop_derivative_s,
//                                   T_h = loop_filter_s (at its lower bound: no filter).
// With h = 1 it is the unity loop of the `error` place (error_loop.hpp); the
// governor_error and governor_pi places are that place and pi_loop with this h. As polynomials,
// with G = N / D, F = nf / df, h = nh / dh:
//   G_new = G0 N nf dh / (G0 D df dh - N nh (df - nf)).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <span>
#include <vector>

#include "rig/diagnose/effects.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {

// The feedback h, what the governor sees of the output y' = y / G0 (the place parameters
// loop_static_share, loop_derivative_s, loop_filter_s), and its output stepped sample by
// sample: h = b + (a - b) / (1 + s T_h), b = T_d / T_h, the low-pass part exact for y' linear
// between samples (model::simulate's hold), l_k = q l_{k-1} + (1 - q) y'_{k-1} + c (y'_k -
// y'_{k-1}), q = exp(-dt / T_h), c = 1 - (T_h / dt)(1 - q); zero before the record (the state the
// models start from).
struct LoopFeedback {
  double static_share = 1.0;
  double derivative_s = 0.0;
  double filter_s = 0.1;
};
class FeedbackFilter {
 public:
  FeedbackFilter(const LoopFeedback& h, double dt_s);
  // h(y') at the current sample, for y' there (the state not advanced).
  double at(double y) const { return rate_ * y + (static_ - rate_) * low_at(y); }
  // Advances the state past the current sample, y' its final value.
  void advance(double y) { low_ = low_at(y), last_ = y; }

 private:
  double low_at(double y) const { return q_ * low_ + (1.0 - q_) * last_ + c_ * (y - last_); }
  double static_, rate_, q_, c_, low_ = 0.0, last_ = 0.0;
};
// h applied to a whole signal.
Eigen::VectorXd feed_back(const LoopFeedback& h, const Eigen::VectorXd& y, double dt_s);

// Whether a place's loop feedback is fitted, and then its h (the last three of the place's
// parameters: governor_loop, governor_error, governor_pi).
bool feedback_fitted(Place place);
LoopFeedback loop_feedback(std::span<const double> place_params);

// One governor, one feedback: in a hypothesis with a linear effect inside the governor's loop
// and an effect on its error at a place that fits the loop's feedback (governor_error,
// governor_pi), the loop is closed with that place's feedback; the linear effect's own three
// are not searched (hypothesis_fit.cpp) and not counted. The two effects' indices, or none.
struct SharedFeedback {
  std::size_t loop = 0, error = 0;
};
std::optional<SharedFeedback> shared_feedback(std::span<const AppliedEffect> effects);
// Sets the loop effect's feedback (its place parameters) to the error place's, when shared.
void share_feedback(std::vector<AppliedEffect>& effects);

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
