// deadband: inputs within +-half_width of the operating point have no effect (blocks.hpp).
// Plant: gov.deadband_pu += R half_width / 100 (plantsim's deadband_pu is the half width on
// the error e: |e| <= db gives 0; half_width is in % of bias).
#include <fmt/format.h>

#include <algorithm>
#include <span>

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
  return deadband(v, p[0]);
}

double apply_on_error(const Params& p, std::span<const double> e, double, double) {
  const double v = e.back();
  return v > p[0] ? v - p[0] : v < -p[0] ? v + p[0] : 0.0;
}

double step(const Params& p, StepState&, double x, double, double) {
  return x > p[0] ? x - p[0] : x < -p[0] ? x + p[0] : 0.0;
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  const double su = pr.scales.u_std;
  if (on_error(e.place))
    return fmt::format(
        "errors within +-{:.3g} ({:.0f} % of the input's standard deviation) have no effect: a "
        "deadband, inside which the governor holds its output",
        p[0], 100.0 * p[0] / su);
  return fmt::format(
      "inputs within +-{:.3g} of the operating point ({:.0f} % of the input's standard "
      "deviation) have no effect: a deadband",
      p[0], 100.0 * p[0] / su);
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  const double r = m.param("gov.r_pu");
  m.set("gov.deadband_pu", m.current("gov.deadband_pu") + r * p[0] / 100.0, name,
        fmt::format("half_width {:.4g} % of bias x R {:.4g} / 100 on the error e", p[0], r));
}

}  // namespace

const EffectModel kDeadbandEffect{
    .id = Effect::kDeadband,
    .name = "deadband",
    .kind = EffectKind::kInputNonlinearity,
    .description = "small input changes about the operating point have no effect",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .apply_on_error = apply_on_error,
    .step = step,
    .explain = meaning,
    .map_to_plant = to_plant,
    .level_shaped = true,
};

}  // namespace rig::diagnose
