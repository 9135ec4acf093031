// The grid's share of the output, taken out before the diagnosis when the recording carries
// the bus frequency (DESIGN.md 5: a `freq_hz` column; the rig records register 3). A set in
// droop on a grid answers every wander of the grid's frequency with power (4 mHz through a
// 4 % droop is 0.2 % of rated power) that the bias did not cause: without the frequency it
// is a slow output disturbance as large as a transducer's drift, and a grid-frequency event
// steps the level. With it, the share is a regression on the frequency through a few lags
// and its rate of change (thresholds.hpp), fitted to the baseline's residual, and removed
// from the recorded output; every fit is then of what the bias and the effects explain.
//
// Used only when the frequency is the grid's: when its coherence with the bias over the
// excited band exceeds kBusFrequencyMaxBiasCoherence the set is islanded (the frequency is
// its own answer to the bias) and the column is left alone, with the reason in the report.
// A constant frequency (a stiff grid's, as plantsim's register reads) leaves y as it is.
#pragma once

#include <Eigen/Core>
#include <string>

namespace rig::diagnose {

struct DiagnoseInput;

struct BusFrequencyShare {
  bool used = false;
  double bias_coherence = 0.0;    // the frequency's with the bias over the excited band
  double frequency_rms_hz = 0.0;  // the frequency's wander about its mean
  double share_rms = 0.0;         // the output's share taken out, output units
  double residual_share = 0.0;    // its share of the baseline residual's variance (0-1)
  // The frequency referred to the governor's input (refer_to_input, bus_frequency.cpp): a
  // in input units per Hz, its standard error, the droop it means (%), and whether u + a f
  // was taken as the input (y then carries a G f).
  double input_per_hz = 0.0;
  double input_per_hz_se = 0.0;
  double droop_pct = 0.0;
  bool referred = false;
  // A grid event: where the share steps (find_level_shift, split.hpp), -1 without one, and
  // the step (the share's mean after it less its mean before, output units): the set's
  // operating point moved there.
  Eigen::Index event_at = -1;
  double event_step = 0.0;
  std::string note;  // one line for the report
};

// Fits the grid's share to input.y - the model's output (with its coupling) and, when the
// frequency is the grid's, removes it from input.y. Throws std::invalid_argument when the
// frequency's length differs from y's or a sample is not finite.
BusFrequencyShare take_out_bus_frequency(DiagnoseInput& input, const Eigen::VectorXd& freq_hz);

}  // namespace rig::diagnose
