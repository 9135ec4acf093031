// resonance: an unmodelled mode (or notch), seeded from the peak of |H1 / G|.
// Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"freq_hz", std::max(4.0 / s.duration_s, 1e-3), 0.45 / s.dt_s, true},
          {"zeta", 0.005, 0.7, true},
          {"peak_ratio", 0.05, 20.0, true}};
}

std::vector<Params> seeds(const Problem&, const Location& loc) {
  const FrequencyLocation& f = loc.freq;
  const double fr = f.peak_ratio_freq_hz > 0.0 ? f.peak_ratio_freq_hz : 0.25 * f.input_band_hz;
  const double band_mid =
      f.band_hz ? std::sqrt(std::max(f.band_hz->first, 1e-3) * f.band_hz->second) : fr;
  return {{fr, 0.05, f.peak_ratio}, {band_mid, 0.1, 1.5}};
}

// (s^2 + 2 zeta r w s + w^2) / (s^2 + 2 zeta w s + w^2): unity away from w, a peak
// of r at w (a notch when r < 1). Scaled by 1/w^2 for conditioning.
void apply(model::TransferFunction& tf, const Params& p) {
  const double w = effects::kTwoPi * p[0], zeta = p[1], r = p[2];
  tf.num = poly_multiply(tf.num, effects::vec({1.0 / (w * w), 2.0 * zeta * r / w, 1.0}));
  tf.den = poly_multiply(tf.den, effects::vec({1.0 / (w * w), 2.0 * zeta / w, 1.0}));
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  const auto& p = e.params;
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
};

}  // namespace rig::diagnose
