// The effect library of `rig diagnose` as one table (DESIGN.md section 9). Each effect's
// knowledge lives in its own file under rig/diagnose/effects/: its word and kind, its
// parameters (named with their unit, ranges from the data's scales), its starting points from
// the location step, how it augments the baseline model (effects.hpp gives the signal path),
// the sentence that explains a fitted value and the plant parameters it maps onto. The code
// that fits, explains and maps hypotheses looks effects up here.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rig/diagnose/effects.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {

struct Problem;
struct Location;
struct HypothesisFit;

using Params = std::vector<double>;                           // as the effect's parameter_specs()
using Derived = std::vector<std::pair<std::string, double>>;  // e.g. the disturbance amplitude

// The output feedback of the feedback effects (augmented_model.cpp):
//   v' = v(t - Td) - cubic z^3 - friction tanh(dz / friction_eps)
struct FeedbackTerms {
  double cubic = 0.0;
  double friction = 0.0;
  double friction_eps = 1.0;
};

// Where an effect's plant mapping writes (rig/cli/diagnose_plant.cpp: a plantsim plant).
class PlantTarget {
 public:
  virtual ~PlantTarget() = default;
  // The plant's value of a "block.name" key.
  virtual double param(const std::string& key) const = 0;
  // The value as changed so far, else the plant's.
  virtual double current(const std::string& key) const = 0;
  // Sets key to value (clamped to the plant's range); reason names the conversion.
  virtual void set(const std::string& key, double value, const std::string& effect,
                   const std::string& reason) = 0;
  virtual void note(const std::string& text) = 0;
};

// The state of a nonlinearity stepped one sample at a time inside a closed loop
// (Place::kPiLoop): its last input and output and its own memory, before the first sample
// not started.
struct StepState {
  bool started = false;
  double last_in = 0.0;
  double last_out = 0.0;
  double memory = 0.0;
};

// What a plant mapping is given: the fitted effect, its hypothesis (the derived values), the
// model it was fitted against and the recorded input.
struct PlantContext {
  const AppliedEffect& effect;
  const HypothesisFit& hypothesis;
  const model::TransferFunction& baseline;
  const Eigen::VectorXd& u;
};

struct EffectModel {
  Effect id = Effect::kGainChange;
  const char* name = "";  // DESIGN.md section 9 word
  EffectKind kind = EffectKind::kLinear;
  const char* description = "";
  std::vector<ParamSpec> (*parameter_specs)(const DataScales& scales) = nullptr;
  std::vector<Params> (*seeds)(const Problem& problem, const Location& location) = nullptr;
  // The change of the linear part (kLinear), if any.
  void (*apply_linear)(model::TransferFunction& tf, const Params& p) = nullptr;
  // The input nonlinearity v -> N(v) (kInputNonlinearity).
  Eigen::VectorXd (*apply_input)(const Problem& problem, const Params& p,
                                 Eigen::VectorXd v) = nullptr;
  // Its form on the governor's error, when it has one: then it is also tried there
  // (Place::kError; rig/diagnose/error_loop.hpp), stepped with the loop. e: the error so
  // far, e.back() the current sample; returns the effect's output at that sample (a
  // memoryless map of e.back(), or a dead time reading e's past). sigma: the standard
  // deviation of the error (as apply_input measures its signal), dt_s its sample period.
  double (*apply_on_error)(const Params& p, std::span<const double> e, double sigma,
                           double dt_s) = nullptr;
  // How many of its leading parameters act there (-1: all); the others (a limiter's
  // recovery_s, which the loop itself does on the error) are neither counted nor reported.
  int params_on_error = -1;
  // Its form stepped one sample at a time (the same map as apply_input, its state in s),
  // when it has one: then it is also tried after the governor's PI, inside its loop
  // (Place::kPiLoop). sigma: the standard deviation of its input, dt_s its sample period.
  double (*step)(const Params& p, StepState& s, double x, double sigma, double dt_s) = nullptr;
  // Its linear part as a rational factor F = num / den with F(0) = 1, when it can sit inside
  // the governor's loop: then it is also tried there (Place::kGovernorLoop,
  // rig/diagnose/governor_loop.hpp): a lag or a transport delay of the actuator or the
  // engine, which the loop works around, unlike one in the transducer.
  void (*loop_factor)(const Params& p, Eigen::VectorXd& num, Eigen::VectorXd& den) = nullptr;
  // Its terms of the output feedback (kFeedback).
  void (*feedback)(const Problem& problem, const Params& p, FeedbackTerms& terms) = nullptr;
  // A disturbance's part of the output's least-squares fit (augmented_model.cpp): columns
  // beside the offset's, and what their fitted coefficients mean ...
  int regressor_columns = 0;
  void (*regressors)(const Problem& problem, const Params& p,
                     Eigen::Ref<Eigen::MatrixXd> columns) = nullptr;
  void (*from_coefficients)(const Eigen::VectorXd& coefficients, Derived& derived) = nullptr;
  // ... and a correction of the fitted output after it.
  void (*after_fit)(const Problem& problem, const Params& p, Eigen::VectorXd& yhat,
                    Derived& derived) = nullptr;
  // What the fitted effect means, with numbers (explain.cpp joins these).
  std::string (*explain)(const AppliedEffect& effect, const HypothesisFit& hypothesis,
                         const Problem& problem) = nullptr;
  // The plant parameters that express it; nullptr: none does.
  void (*map_to_plant)(const PlantContext& context, PlantTarget& plant) = nullptr;
  // The simpler effect this one contains as a special case (hysteresis: backlash), if any:
  // the verdict names the simpler one unless this scores clearly more (diagnose.cpp).
  std::optional<Effect> generalises;
  // Whether it is also tried in the output feedback (placement.hpp, Place::kFeedback).
  bool in_feedback = false;
  // Whether it can be the verdict only when the location's direction test saw the output
  // depend on the input's direction of motion (a play or a hysteresis loop does; with a
  // fitted place and shares it could otherwise stand in for a deadband or a gain).
  bool needs_direction_evidence = false;
  // Whether it is a static map of the signal's level (a deadband, a limit, a curved or kinked
  // map): the level test's evidence (the gain depends on the input's amplitude, which no
  // linear effect does) lets it be the verdict without the margin over a linear effect.
  bool level_shaped = false;
  // Whether the fitted effect carries dynamics of its own (an in-loop limiter's recovery, a
  // boost limiter's air lag), beside its place's; nullptr: a memoryless map.
  bool (*has_memory)(const AppliedEffect& effect, const DataScales& scales) = nullptr;
  // The places it is tried at, of those its forms allow (nullptr: all of them). A limit that
  // follows the engine's air sits only in the governor's output stage: after its PI
  // (Place::kPiLoop, kGovernorPi).
  bool (*tried_at)(Place place) = nullptr;
  // Whether a fitted value can be a verdict (nullptr: any can): one whose shape parameter
  // stopped at its bound is the search's best stand-in for some other shape, not an estimate
  // (a resonance at its largest damping ratio is a broad reshaping of the band).
  bool (*credible)(const AppliedEffect& effect, const DataScales& scales) = nullptr;
};

// Throws std::out_of_range for a value outside the enum.
const EffectModel& effect_model(Effect effect);
// How many of e's parameters act at its place (EffectModel::params_on_error).
std::size_t acting_params(const AppliedEffect& e);
// nullptr for an unknown word.
const EffectModel* effect_model(std::string_view name);
// In the order of kAllEffects.
std::span<const EffectModel* const> all_effect_models();
// Whether effect is the first form of its word (saturation, not its boost limit or soft
// limit; resonance, not its moved modes): a word's cases are its first form's.
bool first_form(Effect effect);

}  // namespace rig::diagnose
