// saturation: limits on the input about the operating point, plain (recovery_s = dt) or
// inside an integrating loop that restores the lost position with recovery_s (blocks.hpp);
// on the governor's error a plain clamp (the loop restores the position there).
// Plant: gov.tmax_pu = rack0 + (u0 + upper) a_r, gov.tmin_pu = rack0 + (u0 - lower) a_r,
// rack0 = the steady rack (P0/P_r)/c at zero bias, u0 the recording's mean bias (a_r and c
// from common.hpp); a limit outside the recorded excursion is not identified: unchanged.
// recovery_s is the plant loop's own restoring time: not mapped.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// recovery_s: dt = a plain limit; longer = inside an integrating loop (blocks.hpp).
std::vector<ParamSpec> specs(const DataScales& s) {
  const double su = std::max(s.u_std, 1e-12);
  return {{"upper_limit", 0.05 * su, 6.0 * su, true},
          {"lower_limit_magnitude", 0.05 * su, 6.0 * su, true},
          {"recovery_s", s.dt_s, effects::recovery_hi_s(s), true}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const DataScales& s = pr.scales;
  const double su = s.u_std;
  return {{1.5 * su, 1.5 * su, s.dt_s}, {2.5 * su, 2.5 * su, s.dt_s}, {1.5 * su, 2.0 * su, 3.0}};
}

Eigen::VectorXd apply(const Problem& pr, const Params& p, Eigen::VectorXd v) {
  return p.size() > 2 ? saturate_in_loop(v, -p[1], p[0], p[2], pr.dt_s) : saturate(v, -p[1], p[0]);
}

// On the governor's error (a limit after a governor whose action is mostly proportional, a
// droop governor's: there a limit of its output is one of its error): a plain clamp, the
// loop itself restores the position (recovery_s has no part there).
double apply_on_error(const Params& p, std::span<const double> e, double, double) {
  return std::clamp(e.back(), -p[1], std::max(-p[1], p[0]));
}

double step(const Params& p, StepState& s, double x, double, double dt_s) {
  const double inc =
      s.started ? x - s.last_in + in_loop_recovery(p[2], dt_s) * (s.last_in - s.last_out) : x;
  s.last_out = std::clamp((s.started ? s.last_out : 0.0) + inc, -p[1], std::max(-p[1], p[0]));
  s.last_in = x;
  s.started = true;
  return s.last_out;
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  const double su = pr.scales.u_std;
  return fmt::format(
      "the input is limited at +{:.3g} / -{:.3g} about the operating point "
      "({:.1f} / {:.1f} standard deviations){}",
      p[0], p[1], p[0] / su, p[1] / su, effects::in_loop_words(e, 2, pr.scales));
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  effects::limits_to_plant(c, m, c.effect.params[0], c.effect.params[1], 0.0);
}

// Inside an integrating loop (recovery_s beyond a sample or two; on the governor's error the
// loop itself restores the position) the limit holds the position it lost: a memory.
bool has_memory(const AppliedEffect& e, const DataScales& s) {
  return !on_error(e.place) && e.params.size() > 2 && e.params[2] > 2.0 * s.dt_s;
}

bool credible(const AppliedEffect& e, const DataScales& s) {
  return effects::recovery_credible(e, 2, s);
}

}  // namespace

const EffectModel kSaturationEffect{
    .id = Effect::kSaturation,
    .name = "saturation",
    .kind = EffectKind::kInputNonlinearity,
    .description = "limits on the input (the actuator's travel), possibly inside a loop",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .apply_on_error = apply_on_error,
    .params_on_error = 2,  // the limits; the loop restores the position there
    .step = step,
    .explain = meaning,
    .map_to_plant = to_plant,
    .level_shaped = true,
    .has_memory = has_memory,
    .credible = credible,
};

}  // namespace rig::diagnose
