// Steps of diagnose() that prepare and post-process the data (split.cpp).
#pragma once

#include <vector>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {

// Validates the input (one-line std::invalid_argument), removes the means, and splits the
// record after a warm-up (4 slowest time constants + dead time, at most 10 %) into
// interleaved blocks: even blocks estimate, odd blocks validate. Interleaving keeps a fault
// that appears part-way through the record in both sets.
Problem prepare_problem(const DiagnoseInput& input, int* blocks, Eigen::Index* warmup);

// When the residual leaves its bounds only in part of the record (5-75 % of it, mostly
// contiguous), input-side effects are fitted on that span only.
void gate_to_windows(Problem& problem, const Location& location);

// An effect present in part of the record only, too weak to locate from the residual alone:
// the fitted hypothesis' own gain per window (baseline minus augmented squared error) is
// tested for a change point (two-sample t over 40 windows, |t| > 4, the quiet side gaining
// under a quarter of the active side); if found, the hypothesis is refitted on that span
// and kept when its validation score rises. Top three input-side hypotheses only.
void refine_onsets(const Problem& problem, std::vector<HypothesisFit>& hypotheses,
                   const Eigen::VectorXd& baseline_yhat, const FitOptions& fit);

// The same for pairs of an input-side effect with a disturbance found behind it
// (search.cpp behind_disturbance): the gain per window is the pair's over the disturbance
// alone (its fit `disturbance`), so that the drift's share does not hide the effect's onset;
// the refit gates the input-side effect only. Top three only; ranked again.
void refine_onsets_beside(const Problem& problem, std::vector<HypothesisFit>& pairs,
                          const HypothesisFit& disturbance, const Eigen::VectorXd& baseline_yhat,
                          const FitOptions& fit);

// An abrupt step of the recorded level (a transducer re-ranged, a gain that changed with the
// operating point in it, a load step): the difference of the residual's means over the
// windows W = max(2 s, 100 samples) after and before each candidate sample k,
//   d_k = mean(r[k, k+W)) - mean(r[k-W, k)),
// against its robust spread over the record (1.4826 x the median absolute deviation): a
// step is where |d_k| exceeds 10 spreads and half the model output's std. Drift and noise
// move d_k smoothly and everywhere; a step only near one k. Returns the sample, or -1.
// spreads: the robust spreads of the window differences a step must exceed
// (thresholds.hpp kLevelShiftSpreads; a grid event in the grid's share, kGridEventSpreads).
Eigen::Index find_level_shift(const Problem& problem, const Eigen::VectorXd& residual,
                              double spreads = thresholds::kLevelShiftSpreads);

// extra_lag and sensor_lag act alike on the input; a sensor lag also filters the noise.
// The residual after the lag is fitted tells them apart: its PSD above 2 fc over its PSD
// below fc/2 (fc = 1/(2 pi T)) is about 1 for noise that bypassed the lag and about
// |1/(1 + j 3)|^2 = 0.1 for noise inside it. The unsupported twin loses one parameter's
// penalty.
void add_sensor_lag_twin(const Problem& problem, std::vector<HypothesisFit>& hypotheses,
                         const FitOptions& fit);

// True when the hypothesis leaves a residual independent of the input (resid test) and
// includes every detected disturbance.
bool explains(const Problem& problem, const HypothesisFit& h, const Location& location);

}  // namespace rig::diagnose
