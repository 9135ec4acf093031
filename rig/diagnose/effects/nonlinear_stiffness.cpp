// nonlinear_stiffness: a cubic output feedback k3 z^3, kappa = the relative incremental
// stiffness change 3 k3 sigma^2 K at one standard deviation sigma of the output, K the
// static gain (augmented_model.cpp closes the loop).
// Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include <algorithm>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales&) {
  return {{"stiffness_change_at_1sd", -0.9, 3.0, false}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const DataScales& s = pr.scales;
  // The cubic term at the peak is (peak/sd)^2 times its value at 1 sd: an output with a
  // high crest factor (an arrow, pulses) makes +-0.1 unstable at its peaks (Silverbox
  // arrow, crest 5.6: +-0.03 already diverges); start at 0.1 (sd/peak)^2 there as well.
  if (s.z_peak_ratio <= 4.0) return {{0.1}, {-0.1}};
  const double c = 0.1 / (s.z_peak_ratio * s.z_peak_ratio);
  return {{0.1}, {-0.1}, {c}, {-c}};
}

void feedback(const Problem& pr, const Params& p, FeedbackTerms& t) {
  const double sz = std::max(pr.scales.z_std, 1e-300);
  t.cubic = p[0] / (3.0 * sz * sz * pr.scales.dc_gain);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  return fmt::format(
      "the stiffness changes with amplitude: {:+.0f} % at one standard deviation of the output",
      100.0 * e.params[0]);
}

}  // namespace

const EffectModel kNonlinearStiffnessEffect{
    .id = Effect::kNonlinearStiffness,
    .name = "nonlinear_stiffness",
    .kind = EffectKind::kFeedback,
    .description = "a restoring force that grows with the cube of the output",
    .parameter_specs = specs,
    .seeds = seeds,
    .feedback = feedback,
    .explain = meaning,
};

}  // namespace rig::diagnose
