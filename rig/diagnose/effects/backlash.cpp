// backlash: play of total width 2 half_width lost at every reversal of the input (blocks.hpp).
// Plant: gov.backlash_pu += 2 half_width a_r (plantsim's backlash_pu is the full play width
// on the rack: rack = xf -+ w/2; a_r from common.hpp).
#include <fmt/format.h>

#include <algorithm>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  const double su = std::max(s.u_std, 1e-12);
  return {{"half_width", 1e-4 * su, 3.0 * su, true}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const double su = pr.scales.u_std;
  return {{0.1 * su}, {0.4 * su}};
}

Eigen::VectorXd apply(const Problem&, const Params& p, Eigen::VectorXd v) {
  return backlash(v, p[0]);
}

double step(const Params& p, StepState& s, double x, double, double) {
  s.last_out = s.started ? std::clamp(s.last_out, x - p[0], x + p[0]) : x;
  s.started = true;
  return s.last_out;
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  const double su = pr.scales.u_std;
  return fmt::format(
      "a reversal of the input is lost for {:.3g} ({:.0f} % of the input's standard "
      "deviation): backlash of total width {:.3g}",
      2 * p[0], 200.0 * p[0] / su, 2 * p[0]);
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  const double a_r = effects::rack_pu_per_pct(m);
  m.set("gov.backlash_pu", m.current("gov.backlash_pu") + 2.0 * p[0] * a_r, name,
        fmt::format("play width 2 x half_width {:.4g} % x {:.4g} pu/% on the rack", p[0], a_r));
}

}  // namespace

const EffectModel kBacklashEffect{
    .id = Effect::kBacklash,
    .name = "backlash",
    .kind = EffectKind::kInputNonlinearity,
    .description = "play in the actuator: part of every reversal of the input is lost",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .step = step,
    .explain = meaning,
    .map_to_plant = to_plant,
    .needs_direction_evidence = true,
};

}  // namespace rig::diagnose
