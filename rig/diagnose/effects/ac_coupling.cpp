// ac_coupling: a high-pass RC s / (RC s + 1) on the output that the model lacks.
// Plant: meas.ac_rc_s = rc_s.
#include <fmt/format.h>

#include <numbers>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"rc_s", 0.02, 0.5 * s.duration_s, true}};
}

std::vector<Params> seeds(const Problem&, const Location&) { return {{5.0}, {30.0}}; }

void apply(model::TransferFunction& tf, const Params& p) {
  tf.num = poly_multiply(tf.num, effects::vec({p[0], 0.0}));
  tf.den = poly_multiply(tf.den, effects::vec({p[0], 1.0}));
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  const auto& p = e.params;
  return fmt::format(
      "the output passed through an AC coupling with RC = {:.2f} s (corner {:.3f} Hz) "
      "that the model lacks",
      p[0], 1.0 / (2.0 * std::numbers::pi * p[0]));
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  m.set("meas.ac_rc_s", p[0], name, fmt::format("rc_s {:.4g} s", p[0]));
}

}  // namespace

const EffectModel kAcCouplingEffect{
    .id = Effect::kAcCoupling,
    .name = "ac_coupling",
    .kind = EffectKind::kLinear,
    .description = "an AC coupling (high-pass RC) of the output that the model lacks",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_linear = apply,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
