// The evidence of the amplitude tests (locate_amplitude.cpp) for a hypothesis's
// nonlinearity, on the whole record or on the hypothesis's own span (an effect from an
// onset is diluted in the whole record's tests): what the verdict (verdict.cpp, docs/
// diagnose.md step 4) asks of a play, a hysteresis loop or a static map before naming it.
#pragma once

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

// Whether h has a play or a hysteresis loop (an effect that needs the direction test).
bool has_direction_effect(const HypothesisFit& h);

// Whether every nonlinearity of h (input-side or in an output feedback) is a static map of
// the level (EffectModel::level_shaped). True for a hypothesis without a nonlinearity.
bool static_maps_only(const HypothesisFit& h);
// ... and each a memoryless one (EffectModel::has_memory: no in-loop recovery, no air lag)
// at a place that fits no dynamics of its own (no place parameters, not in the output's
// feedback): at any one amplitude a gain.
bool memoryless_static_maps_only(const HypothesisFit& h, const DataScales& scales);

// Whether h acts on a span of its own (an onset found for it), not the problem's.
bool spanned_alone(const Problem& pr, const HypothesisFit& h);

// Every effect of h that needs the direction test's evidence has it (thresholds.hpp
// kDirectionEvidenceZ), on the record or on h's own span (span_direction_z).
bool direction_evidenced(const HypothesisFit& h, const Location& loc);

// The direction test beyond any lag shows a play (thresholds.hpp kDirectionBeyondLagZ), on
// the record or on h's own span.
bool play_beyond_lag(const DiagnoseResult& r, const HypothesisFit& h);

// h's nonlinearities are static maps of the level and the level test shows the gain depend
// on the input's amplitude (thresholds.hpp kLevelEvidenceChi2), on the record or h's span.
bool level_evidenced(const DiagnoseResult& r, const HypothesisFit& h);

// For every play or hysteresis loop (at an input-side place) with a span of its own (an
// onset found for it), the direction test repeated on that span (span_direction_z): over
// the whole record an effect from half-way is diluted (gensim seed 5 g044, a hysteresis
// from 60 s: |z| 2.7 on the record, under the evidence bound).
void test_direction_on_spans(DiagnoseResult& r);

// On a two-level input (a PRBS) the input's direction is no evidence, but the signals inside
// the loop and the output still move continuously: a play or hysteresis loop placed there
// that outscores every hypothesis without a direction effect by kTwoLevelPlayMarginPct is
// shown by its fit (fit_shows_direction).
void weigh_plays_on_two_level_input(DiagnoseResult& r);

}  // namespace rig::diagnose
