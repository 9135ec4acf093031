// Fitting a hypothesis (one effect or a pair) to a recording by nonlinear least squares
// (Levenberg-Marquardt, Eigen's MINPACK port, forward-difference Jacobian) on the estimation
// samples, and scoring it on the validation samples.
//
// Bounds: each parameter p in [lo, hi] is searched through an unbounded x,
//   p = lo + (hi - lo) / (1 + e^{-x})         (linear parameters)
//   ln p = ln lo + (ln hi - ln lo) / (1 + e^{-x})   (log-scale parameters)
// so every trial point is admissible. Several starting points (from the location step and
// the parameter range) are tried; the lowest estimation cost wins.
// Score = validation fit gain - penalty_pct_per_parameter * parameters (percentage points).
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {

struct HypothesisFit {
  std::vector<AppliedEffect> effects;
  double fit_before = 0.0, fit_after = 0.0;                        // estimation samples, %
  double validation_fit_before = 0.0, validation_fit_after = 0.0;  // validation samples, %
  double score = 0.0;
  std::vector<std::pair<std::string, double>> derived;
  int evaluations = 0;
  bool screened_only = false;  // searched by the screen alone (diagnose.cpp), not in full
  Eigen::VectorXd yhat;        // the augmented model's output over the whole record
  model::TransferFunction tf;
  Eigen::Index active_from = 0, active_to = -1;  // span the effect acts on (-1: to the end)
  // The direction test's z on that span, for a play or hysteresis loop with a span of its
  // own (evidence.hpp test_direction_on_spans; 0 otherwise).
  double span_direction_z = 0.0;
  // On a two-level input, a play or hysteresis loop inside the loop that outscores every
  // hypothesis without one by the margin (evidence.hpp weigh_plays_on_two_level_input).
  bool fit_shows_direction = false;

  std::string name() const;  // "dead_time" or "dead_time+drift"
  int parameter_count() const;
};

struct FitOptions {
  double penalty_pct_per_parameter = thresholds::kPenaltyPctPerParameter;
  int max_evaluations = 120;  // model simulations per start
  // The starting points with the lowest cost searched from (each is evaluated once first;
  // with two, plantsim's rack limit in seed 1 started from a wrong basin: -96 %, with three 6 %):
  // the others start where the cost is already higher, and each search costs up to
  // max_evaluations simulations of the whole record.
  std::size_t searched_starts = 3;
};

// `starts`: initial parameter sets of the same effects (at least one).
HypothesisFit fit_hypothesis(const Problem& problem,
                             const std::vector<std::vector<AppliedEffect>>& starts,
                             const Eigen::VectorXd& baseline_yhat, const FitOptions& options);

// The hypothesis with these parameters as they are, scored on the problem (no search).
HypothesisFit score_hypothesis(const Problem& problem, std::vector<AppliedEffect> effects,
                               const Eigen::VectorXd& baseline_yhat, const FitOptions& options);

}  // namespace rig::diagnose
