#include "rig/diagnose/gain_peak.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {

// The largest disagreement of gain the data show beyond their uncertainty (thresholds.hpp),
// if any.
std::optional<GainPeak> gain_peak(const Location& loc) {
  double best = std::log(thresholds::kGainPeakRatio), at = -1.0, signed_log = 0.0;
  for (const auto& b : loc.freq.bins) {
    if (!b.significant || !(b.coherence > 0.0) || std::abs(b.model) <= 0.0) continue;
    const double m_eff = std::max(2.0, 0.75 * loc.freq.segments);
    const double rel_error = std::sqrt((1.0 - b.coherence) / (2.0 * m_eff * b.coherence));
    if (rel_error > thresholds::kGainPeakRelError) continue;
    const double ln = std::log(std::abs(b.measured / b.model));
    if (std::abs(ln) >= best) best = std::abs(ln), at = b.freq_hz, signed_log = ln;
  }
  if (at < 0.0) return std::nullopt;
  return GainPeak{at, best, signed_log};
}

// Whether h's own response at the peak (the measured one less that of the residual h
// leaves) takes at least kGainPeakTakenShare of the disagreement's |ln| (thresholds.hpp).
bool accounts_for(const DiagnoseResult& r, const HypothesisFit& h, const GainPeak& peak) {
  if (h.yhat.size() != r.problem.y.size()) return false;
  const FrequencyLocation left = locate_frequency(r.problem, r.problem.y - h.yhat);
  const auto bin =
      std::min_element(left.bins.begin(), left.bins.end(), [&](const auto& a, const auto& b) {
        return std::abs(a.freq_hz - peak.freq_hz) < std::abs(b.freq_hz - peak.freq_hz);
      });
  if (bin == left.bins.end()) return false;
  const std::complex<double> own = bin->measured - bin->residual_response;
  if (std::abs(own) <= 0.0) return false;
  const double left_log = std::abs(std::log(std::abs(bin->measured / own)));
  return left_log <= (1.0 - thresholds::kGainPeakTakenShare) * peak.log_ratio;
}

std::optional<std::pair<double, double>> gain_peak_tells_apart(const DiagnoseResult& r,
                                                               const HypothesisFit& chosen,
                                                               const HypothesisFit& other) {
  const auto peak = gain_peak(r.location);
  if (!peak || !accounts_for(r, chosen, *peak) || accounts_for(r, other, *peak))
    return std::nullopt;
  return std::make_pair(peak->freq_hz, 20.0 * peak->signed_log / std::log(10.0));
}

}  // namespace rig::diagnose
