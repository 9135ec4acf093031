// What the effect files (rig/diagnose/effects/*.cpp) share: their models' declarations for
// the table (effect_registry.cpp) and small helpers.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <initializer_list>
#include <numbers>
#include <string>
#include <vector>

#include "rig/diagnose/effect_registry.hpp"

namespace rig::diagnose {

extern const EffectModel kDeadTimeEffect;
extern const EffectModel kExtraLagEffect;
extern const EffectModel kResonanceEffect;
extern const EffectModel kAcCouplingEffect;
extern const EffectModel kSensorLagEffect;
extern const EffectModel kDeadbandEffect;
extern const EffectModel kBacklashEffect;
extern const EffectModel kHysteresisEffect;
extern const EffectModel kSaturationEffect;
extern const EffectModel kRateLimitEffect;
extern const EffectModel kStaticNonlinearityEffect;
extern const EffectModel kNonlinearStiffnessEffect;
extern const EffectModel kCoulombFrictionEffect;
extern const EffectModel kLoadDampingEffect;
extern const EffectModel kGainChangeEffect;
extern const EffectModel kPeriodicDisturbanceEffect;
extern const EffectModel kDriftEffect;
extern const EffectModel kMovedModesEffect;
extern const EffectModel kBoostLimitEffect;
extern const EffectModel kCurvatureEffect;
extern const EffectModel kSoftLimitEffect;

namespace effects {

inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

Eigen::VectorXd vec(std::initializer_list<double> v);

// A derived value of the fit (e.g. the disturbance amplitude); nan when absent.
double derived_or_nan(const HypothesisFit& h, const std::string& key);
// The same, fallback when absent or not finite.
double derived_or(const HypothesisFit& h, const std::string& key, double fallback);

// The longest recovery_s of the in-loop limiters (saturation, rate_limit).
double recovery_hi_s(const DataScales& s);
// A limiter whose recovery_s (at index i) stopped at that bound is no verdict: the lost
// position hardly comes back within the record, so the fit reached for a slow,
// level-dependent reshaping (an elasto-plastic loop, an AC coupling), not a limit whose
// loop restores it (plantsim's and gensim's limits fit 2-5 s; at the bound only stand-ins
// were seen, gensim seeds 1-2 and a PRBS hysteresis). After the governor's PI (pi_loop) its
// integrator restores the lost position, and a recovery at the bound is the integrator held
// at the limit (anti-windup, gensim's governor): credible there.
bool recovery_credible(const AppliedEffect& e, std::size_t i, const DataScales& s);
// A limit inside an integrating loop loses position that the loop restores slowly: the words
// for recovery_s = p[i], empty for a plain limit.
std::string in_loop_words(const AppliedEffect& e, std::size_t i, const DataScales& s);

// The first-order lag shared by extra_lag (in the plant) and sensor_lag (in the transducer),
// defined in extra_lag.cpp.
std::vector<ParamSpec> lag_parameter_specs(const DataScales& s);
std::vector<Params> lag_seeds(const Problem& pr, const Location& loc);
void lag_apply_linear(model::TransferFunction& tf, const Params& p);

// The governor's scales for the input nonlinearities' plant mappings (plant_scales.cpp). The
// baseline transfer function is plantsim's linearisation: input u = setpoint bias in % of
// rated power P_r, output y = measured power in kW. In the governor (DESIGN.md 7,
// plantsim/plant/governor.hpp) the bias b = u/100 pu enters the error as
// e = Pref + R b - g dw - R Pe_f. Between 1/T4 and 1/T1 (where the excitation lives; T3 = T1
// in the usual tuning) the actuator follows the bias with the gain R K T4 (pu of rack per pu
// of bias; 1 for a kW-controlled set, where r_pu k t4_s = 1 makes 1 % of bias 1 % of rated
// power). So 1 % of bias is a_r = R K T4 / 100 pu on the rack and its rate (0.01 / c, the
// static value, when T4 = 0), and R / 100 pu on the error e.
//
// c = mean injector health (cylinders 1..injectors_out cut): torque = c x rack.
double cylinder_factor(const PlantTarget& p);
// The steady rack position: at rest torque = electrical power (no losses modelled).
double steady_rack_pu(const PlantTarget& p);
// Rack (pu) per % of bias at the excitation's frequencies: a_r = R K T4 / 100.
double rack_pu_per_pct(const PlantTarget& p);
// A limit's sides as gov.tmax_pu, gov.tmin_pu: about the recording's mean input u0 (the
// operating point diagnose removes) the rack is rack0 + u0 a_r. A side beyond the recorded
// excursion by more than reach (how far past it the limit still acts: a dither's) never
// acted, so the fit did not identify it: that side is left as it was.
void limits_to_plant(const PlantContext& c, PlantTarget& m, double upper_limit,
                     double lower_limit_magnitude, double reach);

}  // namespace effects
}  // namespace rig::diagnose
