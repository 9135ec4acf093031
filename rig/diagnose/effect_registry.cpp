// The effect table (effect_registry.hpp) and the functions of effects.hpp and diagnose.hpp
// that answer from it.
#include "rig/diagnose/effect_registry.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <stdexcept>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// In the order of enum class Effect (effect_model() checks it).
constexpr std::array<const EffectModel*, kAllEffects.size()> kTable = {&kDeadTimeEffect,
                                                                       &kExtraLagEffect,
                                                                       &kResonanceEffect,
                                                                       &kAcCouplingEffect,
                                                                       &kSensorLagEffect,
                                                                       &kDeadbandEffect,
                                                                       &kBacklashEffect,
                                                                       &kSaturationEffect,
                                                                       &kRateLimitEffect,
                                                                       &kStaticNonlinearityEffect,
                                                                       &kNonlinearStiffnessEffect,
                                                                       &kCoulombFrictionEffect,
                                                                       &kLoadDampingEffect,
                                                                       &kGainChangeEffect,
                                                                       &kPeriodicDisturbanceEffect,
                                                                       &kDriftEffect,
                                                                       &kHysteresisEffect,
                                                                       &kMovedModesEffect,
                                                                       &kBoostLimitEffect,
                                                                       &kCurvatureEffect,
                                                                       &kSoftLimitEffect};

std::size_t index_of(Effect effect) { return static_cast<std::size_t>(effect); }

}  // namespace

const EffectModel& effect_model(Effect effect) {
  const std::size_t i = index_of(effect);
  if (i >= kTable.size() || kTable[i]->id != effect)
    throw std::out_of_range("effect_model: no model for effect " + std::to_string(i));
  return *kTable[i];
}

const EffectModel* effect_model(std::string_view name) {
  for (const EffectModel* m : kTable)
    if (name == m->name) return m;
  return nullptr;
}

std::span<const EffectModel* const> all_effect_models() { return kTable; }

const char* to_string(Effect effect) {
  return index_of(effect) < kTable.size() ? effect_model(effect).name : "?";
}

std::optional<Effect> effect_from_string(std::string_view word) {
  const EffectModel* m = effect_model(word);
  if (!m) return std::nullopt;
  return m->id;
}

EffectKind kind_of(Effect effect) { return effect_model(effect).kind; }

bool first_form(Effect effect) { return effect_from_string(to_string(effect)) == effect; }

std::size_t acting_params(const AppliedEffect& e) {
  const int n = effect_model(e.effect).params_on_error;
  if (!on_error(e.place) || n < 0) return e.params.size();
  return std::min(e.params.size(), static_cast<std::size_t>(n));
}

std::vector<ParamSpec> parameter_specs(Effect effect, const DataScales& scales) {
  return effect_model(effect).parameter_specs(scales);
}

std::vector<std::vector<double>> seeds_for(Effect effect, const Problem& problem,
                                           const Location& location) {
  return effect_model(effect).seeds(problem, location);
}

}  // namespace rig::diagnose
