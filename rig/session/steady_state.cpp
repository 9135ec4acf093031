#include "rig/session/steady_state.hpp"

#include <fmt/format.h>

#include <cmath>

namespace rig::session {

SteadyStateResult check_steady_state(const std::vector<double>& t_s,
                                     const std::vector<double>& power_kw,
                                     const SteadyStateLimits& limits) {
  SteadyStateResult r;
  r.samples = power_kw.size();
  if (r.samples < 3 || t_s.size() != r.samples) {
    r.reason = "steady-state record too short";
    return r;
  }
  // Least-squares line through (t, P), centred on the mean time for conditioning.
  double t_mean = 0.0;
  double p_mean = 0.0;
  for (std::size_t i = 0; i < r.samples; ++i) {
    if (!std::isfinite(power_kw[i]) || !std::isfinite(t_s[i])) {
      r.reason = fmt::format("non-finite power sample at t = {:.3f} s", t_s[i]);
      return r;
    }
    t_mean += t_s[i];
    p_mean += power_kw[i];
  }
  const double n = static_cast<double>(r.samples);
  t_mean /= n;
  p_mean /= n;
  double stt = 0.0;
  double stp = 0.0;
  for (std::size_t i = 0; i < r.samples; ++i) {
    stt += (t_s[i] - t_mean) * (t_s[i] - t_mean);
    stp += (t_s[i] - t_mean) * (power_kw[i] - p_mean);
  }
  const double slope_kw_per_s = stt > 0.0 ? stp / stt : 0.0;
  double sse = 0.0;
  for (std::size_t i = 0; i < r.samples; ++i) {
    const double e = power_kw[i] - p_mean - slope_kw_per_s * (t_s[i] - t_mean);
    sse += e * e;
  }
  r.p0_kw = p_mean;
  r.duration_s = t_s.back() - t_s.front();
  if (!(p_mean > limits.min_power_kw)) {
    r.reason = fmt::format("power {:.1f} kW is not above the minimum {:.1f} kW (set not loaded?)",
                           p_mean, limits.min_power_kw);
    return r;
  }
  r.noise_pct = 100.0 * std::sqrt(sse / (n - 2.0)) / p_mean;
  r.drift_pct = 100.0 * std::abs(slope_kw_per_s) * r.duration_s / p_mean;
  if (r.noise_pct > limits.max_noise_pct) {
    r.reason = fmt::format("power noise {:.3f} % of P0 exceeds the limit {:.3f} %", r.noise_pct,
                           limits.max_noise_pct);
  } else if (r.drift_pct > limits.max_drift_pct) {
    r.reason = fmt::format("power drift {:.3f} % of P0 over {:.1f} s exceeds the limit {:.3f} %",
                           r.drift_pct, r.duration_s, limits.max_drift_pct);
  } else {
    r.ok = true;
  }
  return r;
}

}  // namespace rig::session
