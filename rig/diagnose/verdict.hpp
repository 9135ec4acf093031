// The verdict of `rig diagnose` (docs/diagnose.md, Method step 4): which of the ranked
// hypotheses the data support, and the word it is called by. Every threshold is named in
// thresholds.hpp with its reason.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

bool has_input_side(const HypothesisFit& h);
bool has_nonlinearity(const HypothesisFit& h);

// Whether h could be a verdict (step 4.2): every fitted value credible (none stopped at a
// bound as a stand-in for another shape) and every play or hysteresis evidenced by the
// direction tests.
bool could_be_verdict(const HypothesisFit& h, const Location& location, const DataScales& scales);

// The best single score of h's disturbances (0 when it has none): what its input-side
// effects must add to.
double disturbance_part_score(const std::vector<HypothesisFit>& hypotheses, const HypothesisFit& h);

// The index of the chosen hypothesis in r.hypotheses (ranked), -1 for none; when it is an
// effect alone because its pair with an immaterial drift was set aside, that pair's index in
// *drift_set_aside (else -1).
int choose(const DiagnoseResult& r, double min_gain_pct, int* drift_set_aside = nullptr);

// The best hypothesis that names another effect, could be a verdict and scores within
// kCloseAlternativePct of the chosen one (or more, when a margin rule chose): the data do
// not tell the two apart. -1 for none. The lag twins and a hysteresis with its play are one.
int close_alternative(const DiagnoseResult& r);

// When nothing is chosen although the input tests failed: a grid event that moved the
// operating point with the residual correlated with the input on one side of it only (or
// over the whole record only), and no other test failing but a sign test that passes on each
// side alone (operating_point.cpp), if that is what the record shows.
std::optional<OperatingPointMove> operating_point_moved(const DiagnoseResult& r);

// Whether r's chosen hypothesis is a memoryless static map of the level that the level test
// did not show, beside such a move (operating_point.cpp): the curved map's answer at the new
// operating point, which the move already accounts for, not a missing effect.
bool map_of_the_move(const DiagnoseResult& r);

// When nothing is chosen although the input tests failed: the best input-side hypothesis
// that could be a verdict, scores above kExplainedBelowMinGainPct (its input-side part too)
// if it is linear or evidenced and leaves a residual independent of the input (verdict.cpp);
// -1 for none, also when that best one is not or does not. choose()'s later preferences (the
// simpler effect, the delay over the lag, an immaterial drift set aside) are not applied.
int explains_below_min_gain(const DiagnoseResult& r);
// The score that rule weighs h by: its score, or for a gain change alone when the step-gain
// test fired (its value fixed by the level's step) the validation fit's rise.
double score_below_min_gain(const DiagnoseResult& r, const HypothesisFit& h);

// The verdict word of a chosen hypothesis.
std::string verdict_of(const HypothesisFit& h);

}  // namespace rig::diagnose
