#include "rig/session/amplitude_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace rig::session {

double pilot_gain_rms(const PilotEstimate& p) {
  if (!(p.excitation_rms_pct > 0.0) || !std::isfinite(p.excitation_rms_pct)) {
    throw std::invalid_argument("amplitude plan: pilot excitation_rms_pct must be finite and > 0");
  }
  if (!std::isfinite(p.response_rms_kw) || !std::isfinite(p.noise_rms_kw) ||
      p.response_rms_kw < 0.0 || p.noise_rms_kw < 0.0) {
    throw std::invalid_argument(
        "amplitude plan: pilot response_rms_kw and noise_rms_kw must be finite and >= 0");
  }
  const double excess = p.response_rms_kw * p.response_rms_kw - p.noise_rms_kw * p.noise_rms_kw;
  return std::sqrt(std::max(excess, 0.0)) / p.excitation_rms_pct;
}

double prior_gain_rms(const std::function<double(double freq_hz)>& magnitude, double bandwidth_hz) {
  if (!magnitude || !(bandwidth_hz > 0.0)) {
    throw std::invalid_argument("amplitude plan: prior needs a model and bandwidth_hz > 0");
  }
  constexpr int kIntervals = 2000;
  const double df = bandwidth_hz / kIntervals;
  double sum = 0.0;
  for (int i = 0; i <= kIntervals; ++i) {
    const double g = magnitude(i * df);
    const double w = (i == 0 || i == kIntervals) ? 0.5 : 1.0;
    sum += w * g * g;
  }
  return std::sqrt(sum * df / bandwidth_hz);
}

AmplitudePlan plan_excitation(double gain_rms, double noise_rms_kw, const AmplitudePlanOptions& o) {
  if (!(o.band_kw > 0.0) || !(o.k_sigma > 0.0) || !(o.gain_margin >= 1.0) ||
      !(o.plan_fraction > 0.0 && o.plan_fraction <= 1.0) || !(o.max_excitation_rms_pct > 0.0)) {
    throw std::invalid_argument(
        "amplitude plan: expected band_kw > 0, k_sigma > 0, gain_margin >= 1, "
        "plan_fraction in (0, 1], max_excitation_rms_pct > 0");
  }
  if (!std::isfinite(gain_rms) || gain_rms < 0.0 || !std::isfinite(noise_rms_kw) ||
      noise_rms_kw < 0.0) {
    throw std::invalid_argument("amplitude plan: gain_rms and noise_rms_kw must be finite, >= 0");
  }
  AmplitudePlan plan;
  plan.gain_rms = gain_rms;
  const double response_rms_allowed = o.plan_fraction * o.band_kw / o.k_sigma - noise_rms_kw;
  if (response_rms_allowed <= 0.0) {
    char line[200];
    std::snprintf(line, sizeof line,
                  "noise %.2f kW rms leaves no room: %.1f sigma of it exceeds %.0f %% of the "
                  "%.1f kW band",
                  noise_rms_kw, o.k_sigma, 100.0 * o.plan_fraction, o.band_kw);
    plan.reason = line;
    return plan;
  }
  const double g = o.gain_margin * gain_rms;
  plan.excitation_rms_pct = g > 0.0 ? std::min(o.max_excitation_rms_pct, response_rms_allowed / g)
                                    : o.max_excitation_rms_pct;
  plan.predicted_peak_kw = o.k_sigma * (g * plan.excitation_rms_pct + noise_rms_kw);
  plan.feasible = true;
  return plan;
}

}  // namespace rig::session
