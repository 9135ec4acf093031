// Where an input-side nonlinearity sits (docs/diagnose.md, "Where it sits"). Knowing only the
// baseline transfer function G (bias -> output), the rig tries each one at three places:
//   input    u -> N -> G                              (on the bias itself)
//   in_loop  u -> F -> k -> N -> 1/k -> G / F,  F = 1/(1 + s T_f) (after the governor's
//            lag: the actuator or the rack; T_f, front_lag_s, is fitted; a
//            Wiener-Hammerstein structure whose linear part is G for any T_f)
//   output   u -> G -> G0 N(. / G0)                   (on the measured output)
//   feedback u - c (y' - N(y')) -> G -> y, y' = y / G0 (a restoring force that depends on
//            the output nonlinearly, as in a nonlinear state-space or linear-fractional
//            model: a hysteretic spring; c, feedback_gain, fitted;
//            only for effects whose model allows it, EffectModel::in_feedback)
//   error    y = G (u - (e - N(e))), e = u - y / G0 (on the error of the governor's loop,
//            as a governor's deadband: G taken as the closed loop of a unity-feedback loop
//            that tracks the bias, L = G' / (1 - G'), G' = G / G0; then y = G0 L N(e) is
//            the same as this form, which needs no L; for effects with a form there,
//            EffectModel::apply_on_error: the memoryless nonlinearities (a limit as a plain
//            clamp), and a dead time
//            (N a delay: a transport delay inside the loop); rig/diagnose/error_loop.hpp)
//   pi_loop  the same loop with N after the governor's PI: a = k C e, C = 1 + 1/(s T_i),
//            y = G (u - C^-1 (a - N(a)) / k): a limit, a play or a hysteresis of the
//            actuator that the loop around it works against (T_i, integral_time_s, fitted;
//            for effects stepped one sample at a time, EffectModel::step)
//   governor_error, governor_pi  the error and pi_loop places with the loop's feedback
//            fitted: e = u - h(y / G0), h as the governor_loop place's
//            (governor_loop.hpp, where a linear effect is placed; a droop
//            governor sees speed, not power)
// At each place the nonlinearity acts on a signal on the bias's scale: in the loop F u times
// k = std(u) / std(F u) (the signal there, as many bias-% as it has the bias's rms: how a
// rack's travel per % of bias is measured), at the output the output over the static gain
// G0. Its parameter is the bias-% equivalent of the value at that place.
#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "rig/diagnose/effects.hpp"
#include "rig/diagnose/error_loop.hpp"
#include "rig/diagnose/governor_loop.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {

struct Problem;
struct Location;

// The places of an input-side nonlinearity (a linear effect's: input, error, governor_loop).
inline constexpr std::array<Place, 8> kAllPlaces = {
    Place::kInput, Place::kInLoop,        Place::kOutput, Place::kFeedback,
    Place::kError, Place::kGovernorError, Place::kPiLoop, Place::kGovernorPi};

// Whether the baseline allows the in-loop place (G / F proper: G strictly proper).
bool in_loop_possible(const model::TransferFunction& tf);

// F's output for the in-loop place (the signal the nonlinearity sees).
Eigen::VectorXd front_signal(const Eigen::VectorXd& v, double front_lag_s, double dt_s);
// k: the in-loop signal w = F u in the bias's rms.
double in_loop_scale(const Problem& problem, const Eigen::VectorXd& w);
// The PI-loop place's signal a = k C e0 on the linear loop's error e0 = u - z0 / G0 (k: in
// the bias's rms, both taken above thresholds::kPiScaleHighPassS) and k.
struct PiSignal {
  Eigen::VectorXd a;
  double k = 1.0;
};
// With `feedback`, e0 = u - h(z0 / G0) (governor_pi).
PiSignal pi_signal(const Problem& problem, const PiGovernor& governor,
                   const LoopFeedback* feedback = nullptr);
// The error of the linear loop, u - z0 / G0, or u - h(z0 / G0) with `feedback`.
Eigen::VectorXd linear_error(const Problem& problem, const LoopFeedback* feedback = nullptr);
// The governor of a pi_loop or governor_pi effect's place parameters (integral_time_s,
// filter_lag_s first).
PiGovernor pi_governor(std::span<const double> place_params);
// G / F: the baseline's linear part after the nonlinearity.
model::TransferFunction rest_after_front(const model::TransferFunction& tf, double front_lag_s);

// The problem as seen at a place: u replaced by the linear signal there (for an effect's
// seeds, which come from the input's scales), for the place's parameters (place_specs).
Problem problem_at(const Problem& problem, Place place, std::span<const double> place_params);

// Whether a fitted place can be part of a verdict: a front lag stopped at its upper bound
// (thresholds.hpp kFrontLagMaxS) is the search reaching for a signal the excitation hardly
// moves, a stand-in for some other shape, not a place in the loop; an integral time at its
// upper bound (kPiIntegralMaxS) is a loop whose integrator takes no part, the stand-in of a
// form on the error itself, and one at its lower bound reaches for a pure integral of the
// error, past any governor's.
bool place_credible(const AppliedEffect& effect);

// Starting points of one effect at one place (the effect's seeds at that place's scales,
// for a few front lags in the loop).
std::vector<std::vector<AppliedEffect>> placed_starts(Effect effect, Place place,
                                                      const Problem& problem,
                                                      const Location& location);

}  // namespace rig::diagnose
