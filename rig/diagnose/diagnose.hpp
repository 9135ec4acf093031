// `rig diagnose`: why a model and a recording disagree (DESIGN.md section 9).
//
// 1. The baseline model is simulated with the recorded input (and the recording's declared
//    AC coupling of the output); the residual r = y - yhat is located in frequency, time and
//    amplitude and tested for whiteness and independence of the input (locate.hpp).
// 2. When the residual is not explained by noise, every applicable effect of the hypothesis
//    library (effects.hpp) is fitted on the estimation blocks, seeded from the location, and
//    scored on the interleaved validation blocks (hypothesis_fit.hpp); pairs are tried when
//    no single effect leaves an input-independent residual.
// 3. Verdict: `none` (no test failed), the effect of the best-scoring hypothesis whose
//    validation gain beats min_gain_pct (or, below it, one that leaves a residual independent
//    of the input when nothing else is chosen), or `unexplained`.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/bus_frequency.hpp"
#include "rig/diagnose/hypothesis_fit.hpp"
#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {

struct DiagnoseInput {
  model::TransferFunction model;
  Eigen::VectorXd u, y;  // recorded input and output (any offset)
  double dt_s = 0.01;
  std::optional<double> output_rc_s;           // the output went through this AC coupling
  std::optional<Eigen::VectorXd> bus_freq_hz;  // the recorded bus frequency (bus_frequency.hpp)
};

struct DiagnoseOptions {
  FitOptions fit;
  double min_gain_pct = thresholds::kMinGainPct;  // validation score (after the penalty)
  bool try_pairs = true;
  int threads = 2;
  std::vector<Effect> effects;  // empty: the whole library
};

// A grid event that moved the set's operating point, the residual correlated with the input
// on one side of it at most (operating_point.cpp operating_point_moved).
struct OperatingPointMove {
  double event_s = 0.0;
  double step = 0.0;               // the grid's share's step there, output units
  bool dependent_after = true;     // the side whose residual is correlated with the input (or
                                   // nearer to it, when neither side is)
  bool one_side_dependent = true;  // false: correlated over the whole record only
  double cross_ratio = 0.0;        // that side's, of the 99 % bound
  double cross_threshold = 0.0;
  std::array<double, 2> sign_z{};  // the sign test before and after it (AmplitudeLocation)
  // The band test (FrequencyLocation::band_hz), when it failed over the record: whether it
  // fails before and after the event alone (on one side at most).
  bool band = false;
  std::array<bool, 2> band_sides{};
  bool correlated = true;  // the cross-correlation failed over the record (or on a half)
};

struct DiagnoseResult {
  std::string verdict;                    // an effect word, "none" or "unexplained"
  std::vector<HypothesisFit> hypotheses;  // ranked by score
  Location location;
  std::string explanation;
  Problem problem;  // the data as diagnosed (means removed, split)
  Eigen::VectorXd baseline_yhat;
  std::optional<double> level_shift_time_s;        // an operating-point step (split.hpp), if any
  double level_shift = 0.0;                        // its size, output units
  std::optional<BusFrequencyShare> bus_frequency;  // when the recording carried one
  std::optional<OperatingPointMove> operating_point_move;  // behind a `none` verdict
  double timing_nuisance_s = 0.0;  // the dead time shift within +-dt/2 absorbed (timing.hpp)
  double fit_before_pct = 0.0;     // whole record after the warm-up
  double validation_fit_before_pct = 0.0;
  int blocks = 0;
  Eigen::Index warmup = 0;
  double elapsed_s = 0.0;
  const HypothesisFit* chosen() const;  // the hypothesis behind the verdict, if any
  int chosen_index = -1;
  // A hypothesis naming another effect that fits about as well (verdict.hpp), -1 for none.
  int alternative_index = -1;
  // The pair "chosen effect + drift" the verdict set aside for its immaterial drift
  // (drift_materiality.hpp), -1 for none.
  int drift_set_aside_index = -1;
  // The chosen hypothesis scores under min_gain_pct but explains what the input tests found
  // (verdict.hpp explains_below_min_gain).
  bool explained_below_min_gain = false;
};

// Throws std::invalid_argument (one line) for mismatched lengths, non-finite samples,
// dt_s <= 0, an improper or unstable model, or a record too short to split.
DiagnoseResult diagnose(const DiagnoseInput& input, const DiagnoseOptions& options = {});

// Starting points of an effect's parameters from the location step.
std::vector<std::vector<double>> seeds_for(Effect effect, const Problem& problem,
                                           const Location& location);

// Plain-language explanation with numbers (explain.cpp).
std::string explain(const DiagnoseResult& result);

}  // namespace rig::diagnose
