// gain_change: the model's gain times gain_ratio, seeded from the median |H1 / G|.
// Plant: meas.gain *= gain_ratio.
#include <fmt/format.h>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales&) { return {{"gain_ratio", 0.2, 5.0, true}}; }

std::vector<Params> seeds(const Problem&, const Location& loc) { return {{loc.freq.gain_ratio}}; }

void apply(model::TransferFunction& tf, const Params& p) { tf.num *= p[0]; }

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  const auto& p = e.params;
  return fmt::format("the gain is {:.3f} times the model's ({:+.1f} %)", p[0],
                     100.0 * (p[0] - 1.0));
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  m.set("meas.gain", m.current("meas.gain") * p[0], name,
        fmt::format("transducer gain x gain_ratio {:.4g}", p[0]));
}

}  // namespace

const EffectModel kGainChangeEffect{
    .id = Effect::kGainChange,
    .name = "gain_change",
    .kind = EffectKind::kLinear,
    .description = "the gain differs from the model's by a constant factor",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_linear = apply,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
