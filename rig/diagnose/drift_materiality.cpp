#include "rig/diagnose/drift_materiality.hpp"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {
namespace {

using thresholds::kDriftClearGainPct;
using thresholds::kDriftMaterialFraction;
using thresholds::kDriftMaterialGainPct;
using thresholds::kDriftMaterialOfLevel;
using thresholds::kOperatingLevelStds;

double derived_of(const HypothesisFit& h, std::string_view name) {
  for (const auto& [key, value] : h.derived)
    if (key == name) return value;
  return 0.0;
}

// h's drift within a power transducer's accuracy of the operating level, on an output that
// carries one. Judged on the half of the record where the drift is larger: a wander from
// half-way is as large there as a steady one of that rms.
bool within_transducer_accuracy(const HypothesisFit& h, const Problem& pr) {
  const double y_std = std::sqrt(pr.y.squaredNorm() / std::max<double>(1.0, pr.y.size()));
  const double level = std::abs(pr.y_level);
  const double rms = std::max(derived_of(h, "drift_rms"), derived_of(h, "drift_rms_worst_half"));
  return level > kOperatingLevelStds * y_std && rms < kDriftMaterialOfLevel * level;
}

}  // namespace

// A drift alone is material when it is large against the input-driven response or the
// operating level, or when modelling it raises the validation fit enough (thresholds.hpp).
bool immaterial_drift(const HypothesisFit& h, const Problem& pr) {
  if (h.effects.size() != 1 || h.effects[0].effect != Effect::kDrift) return false;
  const double gain_pct = h.validation_fit_after - h.validation_fit_before;
  if (gain_pct >= kDriftClearGainPct) return false;
  if (within_transducer_accuracy(h, pr)) return true;
  if (gain_pct >= kDriftMaterialGainPct) return false;
  return derived_of(h, "drift_rms") < kDriftMaterialFraction * pr.scales.z_std;
}

// A pair "effect + drift" whose drift alone is immaterial is reported as the effect alone
// when that single scores min_gain too: the augmented model should not carry the set's
// normal wander as a change. (Beside an effect the wander is not judged by what it adds:
// droopsim's records carry the grid's slow wander, which adds 3.5-5 points beside any
// effect, as much as a 4-6 kW drift effect beside a slew limit adds.)
int without_immaterial_drift(const DiagnoseResult& r, int i, double min_gain) {
  const auto& h = r.hypotheses[static_cast<std::size_t>(i)];
  if (h.effects.size() != 2 || h.effects[1].effect != Effect::kDrift) return i;
  bool drift_immaterial = false;
  int single = -1;
  for (std::size_t j = 0; j < r.hypotheses.size(); ++j) {
    const auto& g = r.hypotheses[j];
    if (g.effects.size() != 1) continue;
    if (g.effects[0].effect == Effect::kDrift) drift_immaterial = immaterial_drift(g, r.problem);
    if (single < 0 && g.effects[0].effect == h.effects[0].effect &&
        g.effects[0].place == h.effects[0].place && g.score >= min_gain)
      single = static_cast<int>(j);  // the same effect at the same place
  }
  return drift_immaterial && single >= 0 ? single : i;
}

const HypothesisFit* set_aside_drift_pair(const DiagnoseResult& r) {
  const int i = r.drift_set_aside_index;
  return i >= 0 && i < static_cast<int>(r.hypotheses.size()) && r.chosen()
             ? &r.hypotheses[static_cast<std::size_t>(i)]
             : nullptr;
}

bool has_drift(const HypothesisFit& h) {
  return std::any_of(h.effects.begin(), h.effects.end(),
                     [](const AppliedEffect& e) { return e.effect == Effect::kDrift; });
}

}  // namespace rig::diagnose
