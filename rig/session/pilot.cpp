#include "rig/session/pilot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/session/amplitude_plan.hpp"

namespace rig::session {
namespace {

double variance(const std::vector<double>& x) {
  if (x.size() < 2) return 0.0;
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double s = 0.0;
  for (double v : x) s += (v - mean) * (v - mean);
  return s / static_cast<double>(x.size() - 1);
}

}  // namespace

PilotResult analyse_pilot(const std::vector<double>& u_pct, const std::vector<double>& y_kw,
                          const PilotPlanLimits& limits) {
  PilotResult r;
  r.band_kw = limits.band_kw;
  r.noise_std_kw = limits.noise_std_kw;
  r.applied_std_pct = std::sqrt(variance(u_pct));
  const double response_rms_kw = std::sqrt(variance(y_kw));
  r.response_std_kw =
      std::sqrt(std::max(response_rms_kw * response_rms_kw - r.noise_std_kw * r.noise_std_kw, 0.0));
  if (!(r.applied_std_pct > 0.0) || !(r.response_std_kw > 0.0)) {
    r.reason = fmt::format("pilot: no measurable response (u std {:.4f} %, response std {:.3f} kW)",
                           r.applied_std_pct, r.response_std_kw);
    return r;
  }
  r.gain_kw_per_pct = pilot_gain_rms({r.applied_std_pct, response_rms_kw, r.noise_std_kw});
  AmplitudePlanOptions o;
  o.band_kw = limits.band_kw;
  o.plan_fraction = limits.plan_fraction;
  o.k_sigma = kPeakFactor;
  o.max_excitation_rms_pct = limits.clamp_pct / limits.input_crest;
  const AmplitudePlan plan = plan_excitation(r.gain_kw_per_pct, r.noise_std_kw, o);
  if (!plan.feasible) {
    r.reason = "pilot: " + plan.reason;
    return r;
  }
  r.planned_std_pct = plan.excitation_rms_pct;
  r.limited_by_clamp = plan.excitation_rms_pct >= o.max_excitation_rms_pct * (1.0 - 1e-9);
  r.predicted_peak_kw = plan.predicted_peak_kw;
  r.ok = true;
  return r;
}

}  // namespace rig::session
