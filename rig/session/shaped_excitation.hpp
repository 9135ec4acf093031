// The shaped excitation (test file `[excitation] type = "shaped"`): a periodic multisine
// designed from the pilot's model so that the predicted OUTPUT, not the input, fills the
// planned part of the band (docs/excitation.md has the theory).
//
//  1. Pilot model: second order plus dead time from the pilot record (after the matched AC
//     coupling): MMFM from its correlations, refined by the time-domain output error.
//  2. Lines: every harmonic of f0 = 1 / (period dt) from f_lo to f_hi (period 1024 samples:
//     10.24 s at 100 Hz, f0 = 0.098 Hz; f_lo, f_hi cover the compare band with room).
//  3. Amplitudes A_k = 1 / |G(f_k)|: a flat output spectrum, which gives every line the same
//     signal-to-noise ratio in the output and so the same relative accuracy of G, the
//     minimax design for an accuracy asked in dB and degrees over a band when the output
//     power is what is limited (less input near the resonance, more elsewhere). The input
//     amplitude limit caps the boost where the plant's gain is small: A_k <= kMaxBoost
//     times the median amplitude.
//  4. Phases: random from the seed, then the output's crest factor minimised by iterative
//     clipping and phase re-projection (Van der Ouderaa, Schoukens and Renneboog 1988).
//  5. Scale: the predicted output peak (times the gain margin) plus 3 noise standard
//     deviations within kOutputPeakFraction of the band, which is below the supervisor's
//     back-off start (60 %), and the input peak within the clamp.
// The supervisor is unchanged; it is told the output's actual crest factor (with the gain
// margin) instead of a Gaussian's 4 for its statistical cap.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "rig/model/transfer_function.hpp"

namespace rig::session {

inline constexpr int kShapedPeriodSamples = 1024;
inline constexpr double kMaxBoost = 3.0;            // input line amplitude / median
inline constexpr double kOutputPeakFraction = 0.5;  // of the band, below the back-off start
inline constexpr double kShapedGainMargin = 1.25;   // the pilot model's gain may be this low
inline constexpr double kClampFraction = 0.9;       // input peak within this of the clamp

struct ShapedLimits {
  double dt_s = 0.01;
  double band_kw = 0.0;
  double noise_std_kw = 0.0;
  double clamp_pct = 5.0;
  double f_lo_hz = 0.25, f_hi_hz = 6.0;
  double ac_coupling_rc_s = 1.6;
  std::uint64_t seed = 1;
};

struct ShapedDesign {
  bool ok = false;
  std::string reason;  // why not, when !ok
  model::TransferFunction pilot_model;
  double dt_s = 0.0;           // sample period of period_pct
  Eigen::VectorXd period_pct;  // one period of the excitation, scaled (% of rated power)
  int lines = 0;
  double f_lo_hz = 0.0, f_hi_hz = 0.0;
  double std_pct = 0.0;            // of the scaled excitation
  double input_crest = 0.0;        // peak / rms of the input
  double output_crest = 0.0;       // peak / rms of the predicted output
  double predicted_peak_kw = 0.0;  // margin * output peak + 3 noise std
  bool limited_by_clamp = false;
};

ShapedDesign design_shaped_excitation(const std::vector<double>& pilot_u,
                                      const std::vector<double>& pilot_y,
                                      const ShapedLimits& limits);

// The excitation of n samples: the period repeated.
Eigen::VectorXd repeat_period(const Eigen::VectorXd& period, Eigen::Index n);

}  // namespace rig::session
