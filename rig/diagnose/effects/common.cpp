#include "rig/diagnose/effects/common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/diagnose/hypothesis_fit.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose::effects {

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) out(i++) = x;
  return out;
}

double derived_or_nan(const HypothesisFit& h, const std::string& key) {
  for (const auto& [k, v] : h.derived)
    if (k == key) return v;
  return std::nan("");
}

double derived_or(const HypothesisFit& h, const std::string& key, double fallback) {
  for (const auto& [k, v] : h.derived)
    if (k == key && std::isfinite(v)) return v;
  return fallback;
}

double recovery_hi_s(const DataScales& s) {
  return std::max(10.0 * s.dt_s, std::min(60.0, s.duration_s / 10.0));
}

bool recovery_credible(const AppliedEffect& e, std::size_t i, const DataScales& s) {
  // The PI's own integrator restores it after the PI; the loop itself on the error.
  if (after_pi(e.place) || on_error(e.place)) return true;
  return e.params.size() <= i || e.params[i] < thresholds::kAtRecoveryBound * recovery_hi_s(s);
}

std::string in_loop_words(const AppliedEffect& e, std::size_t i, const DataScales& s) {
  const auto& p = e.params;
  if (p.size() <= i || on_error(e.place)) return "";  // a plain clamp there (the loop restores)
  if (after_pi(e.place)) {
    if (p[i] >= thresholds::kAtRecoveryBound * recovery_hi_s(s))
      return ", the governor's integrator held while the limit acts (anti-windup)";
    if (p[i] < 5.0 * s.dt_s) return ", the governor's integrator winding up against it";
    return fmt::format(
        ", the integrator's lost travel coming back with a time constant of {:.3g} s "
        "(an anti-windup by back-calculation)",
        p[i]);
  }
  if (p[i] < 5.0 * s.dt_s) return "";
  return fmt::format(
      ", inside an integrating loop (a governor integrator with anti-windup) that restores the "
      "lost position with a time constant of {:.3g} s",
      p[i]);
}

}  // namespace rig::diagnose::effects
