// sensor_lag: extra_lag's first-order lag in the transducer instead of the plant (its
// parameters, seeds and application are extra_lag's); the noise is filtered too, which tells
// it from the plant's (split.cpp).
// Plant: meas.transducer_lag_s += time_constant_s (time constants add, as for extra_lag).
#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {
namespace {

std::string meaning(const AppliedEffect& e, const HypothesisFit& h, const Problem&) {
  const auto& p = e.params;
  const double ratio = effects::derived_or_nan(h, "noise_rolloff_ratio");
  if (!std::isfinite(ratio)) {
    // The corner is too near half the sample rate for two noise bands around it.
    return fmt::format(
        "the measurement lags by {:.0f} ms more than modelled (corner {:.1f} Hz, too near "
        "half the sample rate for the noise to tell the transducer from the plant)",
        1e3 * p[0], 1.0 / (2.0 * std::numbers::pi * p[0]));
  }
  if (ratio < thresholds::kRolloffOwnColourShare * thresholds::kLagWhiteNoiseRolloff) {
    return fmt::format(
        "the measurement lags by {:.0f} ms more than modelled (the noise above the corner is "
        "{:.2f} of that below, a steeper fall than the {:.3f} the lag gives white noise: the "
        "noise has a colour of its own and does not tell the transducer from the plant)",
        1e3 * p[0], ratio, thresholds::kLagWhiteNoiseRolloff);
  }
  return fmt::format(
      "the measurement lags by {:.0f} ms more than modelled; the noise is filtered "
      "too (noise above the corner is {:.2f} of that below), so it is the transducer",
      1e3 * p[0], ratio);
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  m.set("meas.transducer_lag_s", m.current("meas.transducer_lag_s") + p[0], name,
        fmt::format("transducer lag + time_constant_s {:.4g} s (lags add)", p[0]));
}

}  // namespace

const EffectModel kSensorLagEffect{
    .id = Effect::kSensorLag,
    .name = "sensor_lag",
    .kind = EffectKind::kLinear,
    .description = "a first-order lag in the measurement that the model lacks",
    .parameter_specs = effects::lag_parameter_specs,
    .seeds = effects::lag_seeds,
    .apply_linear = effects::lag_apply_linear,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
