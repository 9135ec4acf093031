// A gain the data show beyond their uncertainty (verdict step 5, thresholds.hpp
// kGainPeakRatio): the largest disagreement of |H1/G| with the model, and whether a
// hypothesis's own response takes it.
#pragma once

#include <optional>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

struct GainPeak {
  double freq_hz = 0.0;
  double log_ratio = 0.0;   // |ln |H1 / G||
  double signed_log = 0.0;  // ln |H1 / G|
};

// The largest disagreement of gain the data show beyond their uncertainty, if any.
std::optional<GainPeak> gain_peak(const Location& loc);

// Whether h's own response at the peak (the measured one less that of the residual h
// leaves) takes at least kGainPeakTakenShare of the disagreement's |ln| (thresholds.hpp).
bool accounts_for(const DiagnoseResult& r, const HypothesisFit& h, const GainPeak& peak);

}  // namespace rig::diagnose
