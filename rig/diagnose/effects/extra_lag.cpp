// extra_lag: a first-order lag 1 / (T s + 1) the plant has and the model lacks. Seeded from
// the phase lag. Also tried inside the governor's loop (placement.hpp, "governor_loop"): an
// actuator's or the combustion's lag, which the loop partly works around. Its twin sensor_lag
// (sensor_lag.cpp) is the same lag in the transducer and shares these functions. Plant:
// engine.combustion_lag_s += time_constant_s (time constants add: the sum keeps the lag's
// low-frequency phase, 1st order).
#include <fmt/format.h>

#include <algorithm>
#include <numbers>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"
#include "rig/diagnose/governor_loop.hpp"

namespace rig::diagnose {
namespace effects {

std::vector<ParamSpec> lag_parameter_specs(const DataScales& s) {
  const double lag_lo = s.dt_s / 5.0, lag_hi = std::max(10.0 * s.dt_s, s.duration_s / 20.0);
  return {{"time_constant_s", lag_lo, lag_hi, true}};
}

std::vector<Params> lag_seeds(const Problem& pr, const Location& loc) {
  const FrequencyLocation& f = loc.freq;
  return {{f.lag_from_phase_s > 0.0 ? f.lag_from_phase_s : 0.05}, {5.0 * pr.scales.dt_s}};
}

void lag_apply_linear(model::TransferFunction& tf, const Params& p) {
  tf.den = poly_multiply(tf.den, vec({p[0], 1.0}));
}

}  // namespace effects
namespace {

// Inside the governor's loop: F = 1 / (T s + 1).
void loop_factor(const Params& p, Eigen::VectorXd& num, Eigen::VectorXd& den) {
  num = Eigen::VectorXd::Ones(1);
  den = Eigen::Vector2d(p[0], 1.0);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  const auto& p = e.params;
  return fmt::format("a first-order lag of {:.0f} ms (corner {:.2f} Hz) is missing {}", 1e3 * p[0],
                     1.0 / (2.0 * std::numbers::pi * p[0]),
                     e.place == Place::kGovernorLoop
                         ? "inside the governor's loop (an actuator's or the combustion's lag, "
                           "which the loop works around)"
                         : "in the plant");
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  m.set("engine.combustion_lag_s", m.current("engine.combustion_lag_s") + p[0], name,
        fmt::format("combustion lag + time_constant_s {:.4g} s (lags add)", p[0]));
}

}  // namespace

const EffectModel kExtraLagEffect{
    .id = Effect::kExtraLag,
    .name = "extra_lag",
    .kind = EffectKind::kLinear,
    .description = "a first-order lag in the plant that the model lacks",
    .parameter_specs = effects::lag_parameter_specs,
    .seeds = effects::lag_seeds,
    .apply_linear = effects::lag_apply_linear,
    .loop_factor = loop_factor,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
