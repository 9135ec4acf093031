#include "rig/diagnose/gain_peak.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {

namespace {

// The problem over [from, to) (to -1: the end): the recording's u and y there, the model as
// it is (Welch's segments take each one's mean; a segment's first samples answer inputs
// before it, a leak as small as the model's settling against the segment).
Problem span_of(const Problem& pr, Eigen::Index from, Eigen::Index to) {
  const Eigen::Index end = to < 0 ? pr.y.size() : to;
  Problem sub = pr;
  sub.u = pr.u.segment(from, end - from);
  sub.y = pr.y.segment(from, end - from);
  return sub;
}

// Frequency location of the residual y - yhat over the peak's samples, at its resolution.
FrequencyLocation located_over(const Problem& pr, const Eigen::VectorXd& yhat,
                               const GainPeak& peak) {
  if (peak.from == 0 && peak.to < 0) return locate_frequency(pr, pr.y - yhat, peak.segment_length);
  const Problem sub = span_of(pr, peak.from, peak.to);
  return locate_frequency(sub, sub.y - yhat.segment(peak.from, sub.y.size()), peak.segment_length);
}

// The peak over `where` (its samples and resolution), if any.
std::optional<GainPeak> peak_over(const DiagnoseResult& r, const GainPeak& where) {
  auto peak = gain_peak(Location{.freq = located_over(r.problem, r.baseline_yhat, where)});
  if (peak)
    peak->from = where.from, peak->to = where.to, peak->segment_length = where.segment_length;
  return peak;
}

}  // namespace

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

// The share of the disagreement's |ln| that h's own response at the peak (the measured one
// less that of the residual h leaves) takes: 1 all of it, 0 or less none.
double share_taken(const DiagnoseResult& r, const HypothesisFit& h, const GainPeak& peak) {
  if (h.yhat.size() != r.problem.y.size()) return 0.0;
  const FrequencyLocation left = located_over(r.problem, h.yhat, peak);
  const auto bin =
      std::min_element(left.bins.begin(), left.bins.end(), [&](const auto& a, const auto& b) {
        return std::abs(a.freq_hz - peak.freq_hz) < std::abs(b.freq_hz - peak.freq_hz);
      });
  if (bin == left.bins.end()) return 0.0;
  const std::complex<double> own = bin->measured - bin->residual_response;
  if (std::abs(own) <= 0.0) return 0.0;
  const double left_log = std::abs(std::log(std::abs(bin->measured / own)));
  return 1.0 - left_log / peak.log_ratio;
}

bool accounts_for(const DiagnoseResult& r, const HypothesisFit& h, const GainPeak& peak) {
  return share_taken(r, h, peak) >= thresholds::kGainPeakTakenShare;
}

std::optional<GainPeak> gain_peak(const DiagnoseResult& r, const HypothesisFit& h) {
  if (auto whole = gain_peak(r.location)) return whole;
  const Problem& pr = r.problem;
  const Eigen::Index n = pr.y.size(), to = h.active_to < 0 ? n : h.active_to;
  // As many samples as a span needs (a fitted record has more; a result assembled without a
  // record has none).
  if (r.baseline_yhat.size() != n || n < thresholds::kGainPeakSpanMinSamples) return std::nullopt;
  GainPeak where;
  if (h.active_from > 0 && to - h.active_from >= thresholds::kGainPeakSpanMinSamples)
    where.from = h.active_from, where.to = h.active_to;
  if (where.from > 0)
    if (auto peak = peak_over(r, where)) return peak;
  const Eigen::Index samples = (where.to < 0 ? n : where.to) - where.from;
  where.segment_length =
      std::max<Eigen::Index>(64, welch_segment(samples) / thresholds::kGainPeakCoarserBy);
  return peak_over(r, where);
}

std::optional<GainPeak> gain_peak_tells_apart(const DiagnoseResult& r, const HypothesisFit& chosen,
                                              const HypothesisFit& other) {
  // Over the chosen's samples or the other's (the verdict's step 5 looked over the span of the
  // choice before it, which may be either).
  for (const HypothesisFit* h : {&chosen, &other}) {
    const auto peak = gain_peak(r, *h);
    if (!peak) continue;
    if (accounts_for(r, chosen, *peak) && !accounts_for(r, other, *peak)) return peak;
    if (!accounts_for(r, other, *peak) &&
        (share_taken(r, chosen, *peak) - share_taken(r, other, *peak)) * peak->log_ratio >=
            thresholds::kGainPeakLeadLog)
      return peak;
  }
  return std::nullopt;
}

}  // namespace rig::diagnose
