// Whether a fitted drift is material (docs/diagnose.md, Verdict): a slow wander of a few kW
// is the operating noise of a running set, not a missing effect, unless it is large or
// modelling it raises the fit (thresholds.hpp, "Drift materiality").
#pragma once

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

// A drift alone (h's only effect) that is not material; false for any other hypothesis.
bool immaterial_drift(const HypothesisFit& h, const Problem& problem);

// Hypothesis i of r unless it is a pair "effect + drift" whose drift alone is immaterial: then
// the same effect at the same place alone, when that scores min_gain_pct.
int without_immaterial_drift(const DiagnoseResult& r, int i, double min_gain_pct);

// The pair "chosen effect + drift" the verdict set aside for its immaterial drift
// (r.drift_set_aside_index, from choose()); else nullptr. The explanation says so, and an
// alternative fitted with the drift is judged and compared against this pair.
const HypothesisFit* set_aside_drift_pair(const DiagnoseResult& r);

// Whether h has a drift among its effects.
bool has_drift(const HypothesisFit& h);

}  // namespace rig::diagnose
