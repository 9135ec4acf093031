// The hypothesis library of `rig diagnose` (DESIGN.md section 9): each effect is an
// augmentation of the baseline model with a few physical parameters.
//
// Signal path of an augmented model (effects of each kind compose in this order):
//   u --> input nonlinearity N (deadband, backlash, hysteresis, saturation, rate_limit,
//         static_nonlinearity) --> v; or the same nonlinearity inside the loop or on the
//         output (placement.hpp)
//   v --> baseline G(s) e^{-s Td} modified by the linear effects (dead_time, extra_lag,
//         sensor_lag, resonance, ac_coupling, load_damping, gain_change) --> z,
//         or, with nonlinear_stiffness / coulomb_friction, the rational part in a loop
//         with the output feedback  v' = v(t - Td) - k3 z^3 - Fc tanh(z'/eps)
//   z --> + periodic_disturbance + drift --> the recording's own AC coupling --> yhat
// Parameters are in physical units; their names carry the unit.
// Each effect's model is in its own file, rig/diagnose/effects/<word>.cpp, and the table of
// them in effect_registry.hpp; the functions below answer from that table.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rig::diagnose {

enum class Effect {
  kDeadTime,
  kExtraLag,
  kResonance,
  kAcCoupling,
  kSensorLag,
  kDeadband,
  kBacklash,
  kSaturation,
  kRateLimit,
  kStaticNonlinearity,
  kNonlinearStiffness,
  kCoulombFriction,
  kLoadDamping,
  kGainChange,
  kPeriodicDisturbance,
  kDrift,
  kHysteresis,
  kMovedModes,  // "resonance": the model's own two modes moved together (moved_modes.cpp)
  kBoostLimit,  // "saturation": a limit that follows the engine's air (boost_limit.cpp)
  kCurvature,   // "static_nonlinearity": its one-parameter form, a curvature (curvature.cpp)
  kSoftLimit,   // "saturation": limits whose corners a dither rounds (soft_limit.cpp)
};

inline constexpr std::array<Effect, 21> kAllEffects = {Effect::kDeadTime,
                                                       Effect::kExtraLag,
                                                       Effect::kResonance,
                                                       Effect::kAcCoupling,
                                                       Effect::kSensorLag,
                                                       Effect::kDeadband,
                                                       Effect::kBacklash,
                                                       Effect::kSaturation,
                                                       Effect::kRateLimit,
                                                       Effect::kStaticNonlinearity,
                                                       Effect::kNonlinearStiffness,
                                                       Effect::kCoulombFriction,
                                                       Effect::kLoadDamping,
                                                       Effect::kGainChange,
                                                       Effect::kPeriodicDisturbance,
                                                       Effect::kDrift,
                                                       Effect::kHysteresis,
                                                       Effect::kMovedModes,
                                                       Effect::kBoostLimit,
                                                       Effect::kCurvature,
                                                       Effect::kSoftLimit};

// DESIGN.md section 9 word ("dead_time", ...).
const char* to_string(Effect effect);
std::optional<Effect> effect_from_string(std::string_view word);

enum class EffectKind { kInputNonlinearity, kLinear, kFeedback, kDisturbance };
EffectKind kind_of(Effect effect);

// One fitted parameter: bounds and whether it is searched on a log scale.
struct ParamSpec {
  std::string name;  // with its unit, e.g. "delay_s"
  double lo = 0.0;
  double hi = 1.0;
  bool log_scale = false;
};

// The scales an effect's parameter ranges depend on.
struct DataScales {
  double dt_s = 0.01;
  double duration_s = 100.0;
  double u_std = 1.0;         // input standard deviation
  double u_rate_std = 1.0;    // standard deviation of du/dt
  double z_std = 1.0;         // baseline model output standard deviation
  double z_rate_std = 1.0;    // standard deviation of its rate dz/dt
  double z_peak_ratio = 3.0;  // max |z - mean| over its standard deviation (crest factor)
  double dc_gain = 1.0;       // the baseline's static gain (its peak gain when not finite)
  double delay_s = 0.0;       // the baseline's dead time
  // The baseline's two lightly damped modes that the moved-modes form of a resonance moves
  // (effects/moved_modes.cpp): the one it moves and the one it pulls along; 0: none.
  double moved_mode_hz = 0.0;
  double pulled_mode_hz = 0.0;
};

std::vector<ParamSpec> parameter_specs(Effect effect, const DataScales& scales);

// Where an input-side nonlinearity acts (placement.hpp); other effects are at kInput.
enum class Place {
  kInput,
  kInLoop,
  kOutput,
  kFeedback,
  kError,
  kPiLoop,
  kGovernorLoop,
  kGovernorError,
  kGovernorPi
};
// The error loop's places (error_loop.hpp): on the governor's error, or after its PI; the
// loop's feedback the unity one, or fitted (the governor_ ones, governor_loop.hpp's h).
inline bool on_error(Place p) { return p == Place::kError || p == Place::kGovernorError; }
inline bool after_pi(Place p) { return p == Place::kPiLoop || p == Place::kGovernorPi; }
inline bool in_error_loop(Place p) { return on_error(p) || after_pi(p); }
const char* to_string(Place place);
// How reports name a place: " (in the loop)" after the effect's word ("" at the input), and
// what the augmented model's "acts" field says of it.
const char* place_suffix(Place place);
const char* place_acts(Place place);
// The parameters a place adds to its effect's (in the loop: front_lag_s; after the
// governor's PI: integral_time_s; in the governor's loop: its feedback's shares and filter).
std::vector<ParamSpec> place_specs(Place place, const DataScales& scales);

struct AppliedEffect {
  Effect effect = Effect::kGainChange;
  std::vector<double> params;  // as parameter_specs()
  Place place = Place::kInput;
  std::vector<double> place_params;  // as place_specs()
};

}  // namespace rig::diagnose
