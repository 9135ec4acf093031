// periodic_disturbance: a sinusoid at freq_hz added to the output, not caused by the input;
// its amplitude and phase are fitted by least squares with the offset (augmented_model.cpp).
// Seeded from the residual's strongest spectral line.
// Plant: meas.pickup_hz = freq_hz, meas.pickup_kw = the fitted peak amplitude (plantsim's
// pick-up is A sin(2 pi f t)).
#include <fmt/format.h>

#include <algorithm>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"freq_hz", std::max(2.0 / s.duration_s, 1e-3), 0.499 / s.dt_s, true}};
}

std::vector<Params> seeds(const Problem&, const Location& loc) { return {{loc.dist.line_freq_hz}}; }

std::string meaning(const AppliedEffect& e, const HypothesisFit& h, const Problem&) {
  return fmt::format(
      "a periodic disturbance at {:.3f} Hz of amplitude {:.3g}, not caused by the input",
      e.params[0], effects::derived_or_nan(h, "amplitude"));
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  const double a = effects::derived_or(c.hypothesis, "amplitude", m.current("meas.pickup_kw"));
  m.set("meas.pickup_hz", p[0], name, fmt::format("freq_hz {:.6g}", p[0]));
  m.set("meas.pickup_kw", a, name, fmt::format("fitted amplitude {:.4g} kW", a));
}

}  // namespace

const EffectModel kPeriodicDisturbanceEffect{
    .id = Effect::kPeriodicDisturbance,
    .name = "periodic_disturbance",
    .kind = EffectKind::kDisturbance,
    .description = "a sinusoid in the output not caused by the input (mains pick-up)",
    .parameter_specs = specs,
    .seeds = seeds,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
