// The data a diagnosis works on and the output of the baseline model augmented with
// hypotheses (effects.hpp gives the signal path).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "rig/diagnose/effects.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {

// The recorded output clipped at one end of its range (a sensor's range, a tank that
// overflows): its extreme value piles up (thresholds.hpp kClipMinSamples, kClipPileRatio).
struct OutputClip {
  int side = 0;              // +1 clipped at the top, -1 at the bottom, 0 not clipped
  double level = 0.0;        // where, in the recorded output's units
  Eigen::Index samples = 0;  // how many samples sit there
};
// The clip of a recorded output y, if any (split.cpp).
OutputClip find_output_clip(const Eigen::VectorXd& y);

struct Problem {
  model::TransferFunction tf;  // the baseline model
  double dt_s = 0.01;
  std::optional<double> output_rc_s;  // the recording's declared AC coupling of y only
  Eigen::VectorXd u, y;               // operating point (mean) removed
  Eigen::ArrayXd est_weight;          // 1 on estimation samples, else 0
  Eigen::ArrayXd val_weight;          // 1 on validation samples, else 0
  // Input-side effects act on [active_from, active_to) only (a fault that came and went,
  // located in time); the baseline output elsewhere.
  Eigen::Index active_from = 0;
  Eigen::Index active_to = -1;  // -1: to the end
  DataScales scales;
  Eigen::VectorXd baseline_z;  // simulate(tf, u) before output coupling
  // An abrupt step of the recorded level (an operating-point change) at this sample, fitted
  // as a second offset by every model, the baseline included; -1: none.
  Eigen::Index level_shift_at = -1;
  // Where such a step was found and taken out of y (diagnose.cpp; level_shift_at is then -1).
  Eigen::Index level_step_removed_at = -1;
  double y_level = 0.0;  // the recorded output's mean (the operating level, when it has one)
  // Part of the measurement, as the output coupling is: every model's output is clipped at
  // the recorded clip, whose samples the offset's fit leaves out (augmented_model.cpp).
  OutputClip output_clip;
};

struct ModelOutput {
  Eigen::VectorXd yhat;
  model::TransferFunction tf;                           // the linear part as augmented
  std::vector<std::pair<std::string, double>> derived;  // e.g. the disturbance amplitude
};

// Builds the Problem's derived fields (scales, baseline output) from tf/u/y/dt/weights.
void finish_problem(Problem& problem);

// The augmented model's output for the whole record, including a constant output offset
// (and the periodic disturbance's amplitude and phase) fitted by least squares on the
// estimation samples. Throws std::invalid_argument for a parameter count mismatch.
ModelOutput model_output(const Problem& problem, std::span<const AppliedEffect> effects);

// The linear part of the augmented model (dead time, lags, resonance, coupling, damping,
// gain); effects of other kinds leave it unchanged.
model::TransferFunction augmented_tf(const model::TransferFunction& tf,
                                     std::span<const AppliedEffect> effects);

// Weighted NRMSE fit (DESIGN.md 5) over the samples with weight > 0.
double weighted_fit_pct(const Eigen::VectorXd& y, const Eigen::VectorXd& yhat,
                        const Eigen::ArrayXd& weight);

// The least damped complex pole pair (freq_hz, zeta) of tf's denominator, if any.
std::optional<std::pair<double, double>> dominant_mode(const model::TransferFunction& tf);
// Whether tf has two lightly damped modes apart for the moved-modes form of a resonance
// (effects/moved_modes.cpp).
bool moved_modes_possible(const model::TransferFunction& tf);
// Those two modes' frequencies (Hz): the one the form moves, the one it pulls along.
std::optional<std::pair<double, double>> movable_modes_hz(const model::TransferFunction& tf);
// The moved mode's relative change of frequency (|freq_hz - f0| / f0; infinite without one).
double moved_mode_shift(const model::TransferFunction& tf, double freq_hz);

}  // namespace rig::diagnose
