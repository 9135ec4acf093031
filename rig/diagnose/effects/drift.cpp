// drift: a slow component of the output not caused by the input, estimated by a zero-phase
// smoother of time constant time_constant_s on the residual (augmented_model.cpp). Seeded
// from the location's drift time scale.
// Plant: meas.drift_tau_s = time_constant_s, meas.drift_kw = the fitted drift rms (the
// smoother's time scale approximates the drift's).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// Slow by definition: a short smoother would fit the noise in-sample.
std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"time_constant_s", std::max({20.0 * s.dt_s, 5.0, s.duration_s / 200.0}),
           std::max({40.0 * s.dt_s, 10.0, s.duration_s / 4.0}), true}};
}

std::vector<Params> seeds(const Problem&, const Location& loc) { return {{loc.dist.drift_tau_s}}; }

// The zero-phase smoothed residual of the fitted output is the drift.
void after_fit(const Problem& pr, const Params& p, Eigen::VectorXd& yhat, Derived& derived) {
  const Eigen::VectorXd d = smooth_zero_phase(pr.y - yhat, p[0], pr.dt_s);
  yhat += d;
  derived.emplace_back("drift_rms", std::sqrt(d.array().square().mean()));
  // A drift present in part of the record is judged where it is (drift_materiality.cpp): the larger
  // of the two halves' rms.
  const Eigen::Index half = d.size() / 2;
  const auto rms_of = [](const auto& x) {
    return x.size() ? std::sqrt(x.array().square().mean()) : 0.0;
  };
  derived.emplace_back("drift_rms_worst_half",
                       std::max(rms_of(d.head(half)), rms_of(d.tail(d.size() - half))));
}

std::string meaning(const AppliedEffect& e, const HypothesisFit& h, const Problem&) {
  return fmt::format("a slow drift (time scale {:.0f} s, rms {:.3g}) not caused by the input",
                     e.params[0], effects::derived_or_nan(h, "drift_rms"));
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  m.set("meas.drift_tau_s", p[0], name, fmt::format("time_constant_s {:.4g}", p[0]));
  const double rms = effects::derived_or(c.hypothesis, "drift_rms", m.current("meas.drift_kw"));
  m.set("meas.drift_kw", rms, name, fmt::format("fitted drift rms {:.4g} kW", rms));
}

}  // namespace

const EffectModel kDriftEffect{
    .id = Effect::kDrift,
    .name = "drift",
    .kind = EffectKind::kDisturbance,
    .description = "a slow wander of the output not caused by the input",
    .parameter_specs = specs,
    .seeds = seeds,
    .after_fit = after_fit,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
