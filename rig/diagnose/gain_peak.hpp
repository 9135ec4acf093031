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
  // The samples it was seen over: the whole record, or the span a late effect acts on.
  Eigen::Index from = 0, to = -1;   // -1: to the end
  Eigen::Index segment_length = 0;  // its Welch segments' (0: welch_segment's)
};

// The largest disagreement of gain the data show beyond their uncertainty, if any.
std::optional<GainPeak> gain_peak(const Location& loc);
// That of the whole record or, when it shows none: that of the span h acts on when h acts from
// late in the record (an effect present in a third of the record shows a third of its
// cross-spectrum over the whole), then that of the same samples with Welch segments
// kGainPeakCoarserBy times shorter; if any. None on a record under kGainPeakSpanMinSamples.
std::optional<GainPeak> gain_peak(const DiagnoseResult& r, const HypothesisFit& h);

// Whether h's own response at the peak (the measured one less that of the residual h
// leaves) takes at least kGainPeakTakenShare of the disagreement's |ln| (thresholds.hpp).
bool accounts_for(const DiagnoseResult& r, const HypothesisFit& h, const GainPeak& peak);
// The share of the disagreement's |ln| that h's own response at the peak takes: 1 all of it,
// 0 none (or h leaves it larger).
double share_taken(const DiagnoseResult& r, const HypothesisFit& h, const GainPeak& peak);

// When the data show a gain peak that `chosen` accounts for and `other` does not, or of which
// `chosen` takes more than `other` by kGainPeakLeadLog (thresholds.hpp): the peak.
std::optional<GainPeak> gain_peak_tells_apart(const DiagnoseResult& r, const HypothesisFit& chosen,
                                              const HypothesisFit& other);

}  // namespace rig::diagnose
