// saturation, second form: a fuel limit that follows the engine's air (a smoke or boost
// limiter). The governor's demand x (about the operating point) is held below
//   limit = upper_limit + follow_share * m,   m = the limited demand through a lag air_lag_s
// : the turbocharger's air follows the fuel with its own lag and the limiter lets through
// only as much more fuel as the air burns cleanly, so the limit rises with the fuel of the
// last second or two and a fast rise of the demand is cut while a slow one passes. A fixed
// limit (first form, saturation.cpp) is follow_share 0 without the lower limit.
//
// It sits in the governor's output stage, so it is tried only after the governor's PI (both
// pi_loop places); on droopsim's smoke limiter the fixed limit fitted 0.15-10 points under
// a static map there (s1 d029, s2 d028: named static_nonlinearity).
//
// Plant: plantsim's MAP limiter (engine.hpp: f_l = min(f_d, F0 + Fb boost), Tb boost' =
// c f_l - boost) about the steady rack rack0 (boost0 = c rack0), in bias % through a_r:
// engine.boost_lag_s = air_lag_s, engine.map_fuel_gain = follow_share / c,
// engine.map_fuel_min_pu = rack0 + upper_limit a_r - follow_share rack0.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// The air path's lag: from a small turbocharger's few tenths of a second to a large one's
// several seconds.
constexpr double kAirLagLoS = 0.1, kAirLagHiS = 6.0;
// The limit's rise per unit of lagged fuel: 0 is a fixed limit, about 1 a limiter whose
// margin scales with the air (air roughly proportional to fuel at load).
constexpr double kFollowShareHi = 1.5;

std::vector<ParamSpec> specs(const DataScales& s) {
  const double su = std::max(s.u_std, 1e-12);
  return {{"upper_limit", 0.05 * su, 6.0 * su, true},
          {"follow_share", 0.0, kFollowShareHi, false},
          {"air_lag_s", kAirLagLoS, kAirLagHiS, true}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const double su = pr.scales.u_std;
  return {{1.0 * su, 0.8, 1.2}, {0.5 * su, 1.0, 1.2}, {1.5 * su, 0.5, 0.5}};
}

double step(const Params& p, StepState& s, double x, double, double dt_s) {
  const double a = std::exp(-dt_s / std::max(p[2], 1e-9));
  const double out = std::min(x, p[0] + p[1] * s.memory);
  s.memory = a * s.memory + (1.0 - a) * out;
  s.last_in = x, s.last_out = out, s.started = true;
  return out;
}

Eigen::VectorXd apply(const Problem& pr, const Params& p, Eigen::VectorXd v) {
  StepState s;
  for (Eigen::Index k = 0; k < v.size(); ++k) v(k) = step(p, s, v(k), 0.0, pr.dt_s);
  return v;
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  return fmt::format(
      "the governor's demand is limited at +{:.3g} ({:.1f} standard deviations) above the "
      "operating point plus {:.2f} of its own value through a {:.2g} s lag: a fuel limit that "
      "follows the engine's air (a smoke or boost limiter), which cuts a fast rise and lets a "
      "slow one through",
      p[0], p[0] / std::max(pr.scales.u_std, 1e-12), p[1], p[2]);
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const auto& p = c.effect.params;
  const double cyl = effects::cylinder_factor(m), rack0 = effects::steady_rack_pu(m);
  const double a_r = effects::rack_pu_per_pct(m);
  m.set("engine.boost_lag_s", p[2], "saturation", "the limit's air lag");
  m.set("engine.map_fuel_gain", p[1] / cyl, "saturation",
        fmt::format("follow_share {:.4g} / mean injector health {:.4g}", p[1], cyl));
  m.set("engine.map_fuel_min_pu", rack0 + p[0] * a_r - p[1] * rack0, "saturation",
        fmt::format("steady rack {:.4g} pu + upper_limit {:.4g} % x {:.4g} pu/% - follow_share "
                    "x steady rack",
                    rack0, p[0], a_r));
}

}  // namespace

const EffectModel kBoostLimitEffect{
    .id = Effect::kBoostLimit,
    .name = "saturation",
    .kind = EffectKind::kInputNonlinearity,
    .description =
        "a fuel limit that follows the engine's air (smoke limiter), after the "
        "governor",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .step = step,
    .explain = meaning,
    .map_to_plant = to_plant,
    .level_shaped = true,
    .has_memory = [](const AppliedEffect&, const DataScales&) { return true; },  // its air lag
    .tried_at = after_pi,
};

}  // namespace rig::diagnose
