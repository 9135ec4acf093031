// coulomb_friction: an output feedback Fc tanh(dz / eps) opposing every motion, eps = 5 % of
// the output rate's standard deviation (augmented_model.cpp closes the loop).
// Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include <algorithm>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  const double su = std::max(s.u_std, 1e-12);
  return {{"friction", 1e-3 * su, 2.0 * su, true}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const double su = pr.scales.u_std;
  return {{0.05 * su}, {0.2 * su}};
}

void feedback(const Problem& pr, const Params& p, FeedbackTerms& t) {
  t.friction = p[0];
  t.friction_eps = 0.05 * std::max(pr.scales.z_rate_std, 1e-300);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  const double su = pr.scales.u_std;
  return fmt::format(
      "a friction force of {:.3g} (in input units, {:.0f} % of the input's standard "
      "deviation) opposes every motion",
      p[0], 100.0 * p[0] / su);
}

}  // namespace

const EffectModel kCoulombFrictionEffect{
    .id = Effect::kCoulombFriction,
    .name = "coulomb_friction",
    .kind = EffectKind::kFeedback,
    .description = "a constant friction force opposing every motion of the output",
    .parameter_specs = specs,
    .seeds = seeds,
    .feedback = feedback,
    .explain = meaning,
};

}  // namespace rig::diagnose
