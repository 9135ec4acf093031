// resonance: an unmodelled mode, as a peak (or notch) on the model or in series with it (a
// shaft or coupling mode at or above the edge of the excited band, seen there as a gain
// that grows with frequency), seeded from the peak of |H1 / G| and above the band.
// Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// A mode's damping ratio is at most this: above it a second-order factor has almost no
// peak (x1.25 at most; none beyond 1/sqrt(2)) and is a broad reshaping of the band that a
// lag, a gain or an in-loop effect explains with fewer parameters.
constexpr double kMaxModeDamping = 0.4;
// hf_gain below this reads as a mode in series (the model's own gain rolls off above it).
constexpr double kSeriesModeBelow = 0.5;

// A peak or notch whose fitted damping ratio is this close to kMaxModeDamping stopped at
// the bound: the data asked for a broader shape than a mode (a lag or an in-loop effect seen
// through the loop), and the fit is no evidence of a mode at its frequency. A mode in series
// at or above the band's edge is exempt: only its low-frequency flank is seen, which fixes
// its frequency and leaves its damping free.
constexpr double kAtDampingBound = 0.98 * kMaxModeDamping;

// The moved-mode seed starts this far below the model's mode (a few percent of stiffness).
constexpr double kMovedModeSeedRatio = 0.95;

bool credible(const AppliedEffect& e, const DataScales&) {
  return e.params[1] < kAtDampingBound || e.params[3] < kSeriesModeBelow;
}

std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"freq_hz", std::max(4.0 / s.duration_s, 1e-3), 0.45 / s.dt_s, true},
          {"zeta", 0.005, kMaxModeDamping, true},
          {"peak_ratio", 0.05, 20.0, true},
          {"hf_gain", 0.0, 1.0, false}};
}

std::vector<Params> seeds(const Problem& pr, const Location& loc) {
  const FrequencyLocation& f = loc.freq;
  const double fr = f.peak_ratio_freq_hz > 0.0 ? f.peak_ratio_freq_hz : 0.25 * f.input_band_hz;
  const double band_mid =
      f.band_hz ? std::sqrt(std::max(f.band_hz->first, 1e-3) * f.band_hz->second) : fr;
  const double above_band = std::min(1.2 * f.input_band_hz, 0.4 / pr.dt_s);
  std::vector<Params> out{{fr, 0.05, f.peak_ratio, 1.0},
                          {band_mid, 0.1, 1.5, 1.0},
                          {above_band, 0.1, 0.05, 0.0},
                          {0.7 * above_band, 0.2, 0.05, 0.0}};
  // The model's own mode moved down (a softer shaft or coupling pulls the electromechanical
  // mode with it): the factor's zeros near the old mode cancel it, its poles sit below.
  if (const auto mode = dominant_mode(pr.tf); mode && mode->second < kMaxModeDamping)
    out.push_back({kMovedModeSeedRatio * mode->first, mode->second, 1.0,
                   kMovedModeSeedRatio * kMovedModeSeedRatio});
  return out;
}

// (a s^2 + 2 zeta r w s + w^2) / (s^2 + 2 zeta w s + w^2) with a = hf_gain: at a = 1
// unity away from w and a peak of r at w (a notch when r < 1); at a = 0 a mode in series,
// rolling off above w. Unity at DC. Scaled by 1/w^2 for conditioning.
void apply(model::TransferFunction& tf, const Params& p) {
  const double w = effects::kTwoPi * p[0], zeta = p[1], r = p[2], a = p[3];
  tf.num = poly_multiply(tf.num, effects::vec({a / (w * w), 2.0 * zeta * r / w, 1.0}));
  tf.den = poly_multiply(tf.den, effects::vec({1.0 / (w * w), 2.0 * zeta / w, 1.0}));
}

// The factor's zeros, at w / sqrt(hf_gain), cancel a mode of the model this close to them
// (relative frequency): the model's mode has moved to the factor's poles.
constexpr double kSameModeFrequency = 0.1;

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  const auto mode = dominant_mode(pr.tf);
  if (p[3] >= kSeriesModeBelow && mode) {
    const double zeros_hz = p[0] / std::sqrt(p[3]);
    if (std::abs(zeros_hz - mode->first) <= kSameModeFrequency * mode->first)
      return fmt::format(
          "the model's mode at {:.2f} Hz (damping ratio {:.3f}) has moved to {:.2f} Hz (damping "
          "ratio {:.3f}): a change of the stiffness or inertia behind it, e.g. a softer shaft "
          "or coupling",
          mode->first, mode->second, p[0], p[1]);
  }
  if (p[3] < kSeriesModeBelow)
    return fmt::format(
        "an unmodelled mode in series with the model at {:.2f} Hz (damping ratio {:.3f}; a "
        "shaft or coupling mode: the gain grows towards it, x{:.2f} at {:.2f} Hz)",
        p[0], p[1], 1.0 / (2.0 * p[1]), p[0]);
  return fmt::format(
      "an unmodelled resonance at {:.2f} Hz (damping ratio {:.3f}, gain x{:.2f} at its peak)", p[0],
      p[1], p[2]);
}

}  // namespace

const EffectModel kResonanceEffect{
    .id = Effect::kResonance,
    .name = "resonance",
    .kind = EffectKind::kLinear,
    .description = "an unmodelled mode: a gain peak (or notch) with its damping",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_linear = apply,
    .explain = meaning,
    // At the model's own mode with hf_gain 1 it is a change of that mode's damping.
    .generalises = Effect::kLoadDamping,
    .credible = credible,
};

}  // namespace rig::diagnose
