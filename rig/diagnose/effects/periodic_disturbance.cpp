// periodic_disturbance: a sinusoid at freq_hz added to the output, not caused by the input;
// its amplitude and phase are fitted by least squares with the offset (augmented_model.cpp).
// Seeded from the residual's strongest spectral line.
// Plant: meas.pickup_hz = freq_hz, meas.pickup_kw = the fitted peak amplitude (plantsim's
// pick-up is A sin(2 pi f t)).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"freq_hz", std::max(2.0 / s.duration_s, 1e-3), 0.499 / s.dt_s, true}};
}

std::vector<Params> seeds(const Problem&, const Location& loc) { return {{loc.dist.line_freq_hz}}; }

// cos and sin at freq_hz: their coefficients give the amplitude and phase.
void regressors(const Problem& pr, const Params& p, Eigen::Ref<Eigen::MatrixXd> x) {
  const Eigen::Index n = x.rows();
  const Eigen::ArrayXd t = Eigen::ArrayXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * pr.dt_s;
  x.col(0) = (effects::kTwoPi * p[0] * t).cos().matrix();
  x.col(1) = (effects::kTwoPi * p[0] * t).sin().matrix();
}

void from_coefficients(const Eigen::VectorXd& beta, Derived& derived) {
  derived.emplace_back("amplitude", std::hypot(beta(0), beta(1)));
  derived.emplace_back("phase_deg", std::atan2(-beta(1), beta(0)) * 180.0 / std::numbers::pi);
}

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
    .regressor_columns = 2,
    .regressors = regressors,
    .from_coefficients = from_coefficients,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
