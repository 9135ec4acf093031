// The sampling convention as a nuisance (docs/diagnose.md, "Timing"). Whether the recorded
// input is read as held for a sample or interpolated between samples, and whether the output
// is sampled at the row's start or its end, moves the model's response by up to half a
// sample. That is not physics: when the baseline with its dead time shifted by the best
// delta within +-dt/2 (never below zero) leaves nothing to explain, the verdict is `none`
// (diagnose.cpp); otherwise the effects are fitted against the model as given (a shift would
// take part of a lag or a play), and a dead time of at most half a sample is never a verdict.
#pragma once

namespace rig::diagnose {

struct Problem;

// Shifts problem.tf's dead time by the estimation fit's best delta in [-dt/2, dt/2] (not
// below zero) and rebuilds its derived fields; returns delta (0: no shift helped).
double absorb_timing_nuisance(Problem& problem);

}  // namespace rig::diagnose
