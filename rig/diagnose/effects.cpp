#include "rig/diagnose/effects.hpp"

#include <algorithm>
#include <cmath>

namespace rig::diagnose {

const char* to_string(Effect effect) {
  switch (effect) {
    case Effect::kDeadTime:
      return "dead_time";
    case Effect::kExtraLag:
      return "extra_lag";
    case Effect::kResonance:
      return "resonance";
    case Effect::kAcCoupling:
      return "ac_coupling";
    case Effect::kSensorLag:
      return "sensor_lag";
    case Effect::kDeadband:
      return "deadband";
    case Effect::kBacklash:
      return "backlash";
    case Effect::kSaturation:
      return "saturation";
    case Effect::kRateLimit:
      return "rate_limit";
    case Effect::kStaticNonlinearity:
      return "static_nonlinearity";
    case Effect::kNonlinearStiffness:
      return "nonlinear_stiffness";
    case Effect::kCoulombFriction:
      return "coulomb_friction";
    case Effect::kLoadDamping:
      return "load_damping";
    case Effect::kGainChange:
      return "gain_change";
    case Effect::kPeriodicDisturbance:
      return "periodic_disturbance";
    case Effect::kDrift:
      return "drift";
  }
  return "?";
}

std::optional<Effect> effect_from_string(std::string_view word) {
  for (Effect e : kAllEffects) {
    if (word == to_string(e)) return e;
  }
  return std::nullopt;
}

EffectKind kind_of(Effect effect) {
  switch (effect) {
    case Effect::kDeadband:
    case Effect::kBacklash:
    case Effect::kSaturation:
    case Effect::kRateLimit:
    case Effect::kStaticNonlinearity:
      return EffectKind::kInputNonlinearity;
    case Effect::kNonlinearStiffness:
    case Effect::kCoulombFriction:
      return EffectKind::kFeedback;
    case Effect::kPeriodicDisturbance:
    case Effect::kDrift:
      return EffectKind::kDisturbance;
    default:
      return EffectKind::kLinear;
  }
}

std::vector<ParamSpec> parameter_specs(Effect effect, const DataScales& s) {
  const double lag_lo = s.dt_s / 5.0, lag_hi = std::max(10.0 * s.dt_s, s.duration_s / 20.0);
  const double su = std::max(s.u_std, 1e-12);
  const double recovery_hi = std::max(10.0 * s.dt_s, std::min(60.0, s.duration_s / 10.0));
  switch (effect) {
    case Effect::kDeadTime:
      return {{"extra_delay_s", -s.delay_s, std::min(2.0, 0.05 * s.duration_s), false}};
    case Effect::kExtraLag:
    case Effect::kSensorLag:
      return {{"time_constant_s", lag_lo, lag_hi, true}};
    case Effect::kResonance:
      return {{"freq_hz", std::max(4.0 / s.duration_s, 1e-3), 0.45 / s.dt_s, true},
              {"zeta", 0.005, 0.7, true},
              {"peak_ratio", 0.05, 20.0, true}};
    case Effect::kAcCoupling:
      return {{"rc_s", 0.02, 0.5 * s.duration_s, true}};
    case Effect::kDeadband:
    case Effect::kBacklash:
      return {{"half_width", 1e-4 * su, 3.0 * su, true}};
    // recovery_s: dt = a plain limit; longer = inside an integrating loop (blocks.hpp).
    case Effect::kSaturation:
      return {{"upper_limit", 0.05 * su, 6.0 * su, true},
              {"lower_limit_magnitude", 0.05 * su, 6.0 * su, true},
              {"recovery_s", s.dt_s, recovery_hi, true}};
    case Effect::kRateLimit:
      return {{"rate_limit_per_s", 0.02 * std::max(s.u_rate_std, 1e-12),
               10.0 * std::max(s.u_rate_std, 1e-12), true},
              {"recovery_s", s.dt_s, recovery_hi, true}};
    case Effect::kStaticNonlinearity:
      return {{"quadratic_rel", -0.6, 0.6, false}, {"cubic_rel", -0.3, 0.3, false}};
    case Effect::kNonlinearStiffness:
      return {{"stiffness_change_at_1sd", -0.9, 3.0, false}};
    case Effect::kCoulombFriction:
      return {{"friction", 1e-3 * su, 2.0 * su, true}};
    case Effect::kLoadDamping:
      return {{"zeta", 0.005, 1.5, true}};
    case Effect::kGainChange:
      return {{"gain_ratio", 0.2, 5.0, true}};
    case Effect::kPeriodicDisturbance:
      return {{"freq_hz", std::max(2.0 / s.duration_s, 1e-3), 0.499 / s.dt_s, true}};
    case Effect::kDrift:
      // Slow by definition: a short smoother would fit the noise in-sample.
      return {{"time_constant_s", std::max({20.0 * s.dt_s, 5.0, s.duration_s / 200.0}),
               std::max({40.0 * s.dt_s, 10.0, s.duration_s / 4.0}), true}};
  }
  return {};
}

}  // namespace rig::diagnose
