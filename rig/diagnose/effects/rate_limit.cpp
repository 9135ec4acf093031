// rate_limit: the input cannot change faster than rate_limit_per_s, plain (recovery_s = dt)
// or inside an integrating loop (blocks.hpp).
// Plant: gov.rate_limit_pu_s = rate_limit_per_s a_r (on the actuator rate; a_r from
// common.hpp). recovery_s is the plant loop's own restoring time: not mapped.
#include <fmt/format.h>

#include <algorithm>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"rate_limit_per_s", 0.02 * std::max(s.u_rate_std, 1e-12),
           10.0 * std::max(s.u_rate_std, 1e-12), true},
          {"recovery_s", s.dt_s, effects::recovery_hi_s(s), true}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const DataScales& s = pr.scales;
  return {{0.5 * s.u_rate_std, s.dt_s}, {1.5 * s.u_rate_std, s.dt_s}, {1.5 * s.u_rate_std, 3.0}};
}

Eigen::VectorXd apply(const Problem& pr, const Params& p, Eigen::VectorXd v) {
  return p.size() > 1 ? rate_limit_in_loop(v, p[0], p[1], pr.dt_s) : rate_limit(v, p[0], pr.dt_s);
}

double step(const Params& p, StepState& s, double x, double, double dt_s) {
  const double limit = p[0] * dt_s;
  if (s.started)
    s.last_out += std::clamp(
        x - s.last_in + in_loop_recovery(p[1], dt_s) * (s.last_in - s.last_out), -limit, limit);
  else
    s.last_out = x;
  s.last_in = x;
  s.started = true;
  return s.last_out;
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  return fmt::format("the input cannot change faster than {:.3g} per second{}", p[0],
                     effects::in_loop_words(e, 1, pr.scales));
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  const double a_r = effects::rack_pu_per_pct(m);
  m.set("gov.rate_limit_pu_s", p[0] * a_r, name,
        fmt::format("rate_limit_per_s {:.4g} %/s x {:.4g} pu/% on the actuator", p[0], a_r));
}

bool credible(const AppliedEffect& e, const DataScales& s) {
  return effects::recovery_credible(e, 1, s);
}

}  // namespace

const EffectModel kRateLimitEffect{
    .id = Effect::kRateLimit,
    .name = "rate_limit",
    .kind = EffectKind::kInputNonlinearity,
    .description = "a limit on the input's rate of change (the actuator's speed)",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .step = step,
    .explain = meaning,
    .map_to_plant = to_plant,
    .credible = credible,
};

}  // namespace rig::diagnose
