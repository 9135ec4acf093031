// The governor's scales the input nonlinearities map through (common.hpp gives the
// derivation).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose::effects {

double cylinder_factor(const PlantTarget& p) {
  const int n = static_cast<int>(std::lround(p.param("engine.cylinders")));
  const int out = static_cast<int>(std::lround(p.param("engine.injectors_out")));
  double sum = 0.0;
  for (int k = 0; k < n; ++k)
    sum += k < out ? 0.0 : p.param(fmt::format("engine.injector_{}", k + 1));
  return std::max(sum / n, 1e-9);
}

double steady_rack_pu(const PlantTarget& p) {
  return p.param("op.power_kw") / p.param("op.rated_kw") / cylinder_factor(p);
}

double rack_pu_per_pct(const PlantTarget& p) {
  const double t4 = p.param("gov.t4_s");
  if (t4 > 0.0) return p.param("gov.r_pu") * p.param("gov.k") * t4 / 100.0;
  return 0.01 / cylinder_factor(p);  // static: 1 % of rated power needs 0.01/c of rack
}

void limits_to_plant(const PlantContext& c, PlantTarget& m, double upper_limit,
                     double lower_limit_magnitude, double reach) {
  const Eigen::VectorXd& u = c.u;
  const double u0 = u.size() ? u.mean() : 0.0;
  const double up = u.size() ? u.maxCoeff() - u0 + reach : INFINITY;
  const double down = u.size() ? u0 - u.minCoeff() + reach : INFINITY;
  const double a_r = rack_pu_per_pct(m);
  const double rack = steady_rack_pu(m) + u0 * a_r;
  const std::pair<const char*, double> sides[] = {{"upper_limit", upper_limit},
                                                  {"lower_limit_magnitude", lower_limit_magnitude}};
  for (const auto& [word, lim] : sides) {
    const bool upper = std::string(word) == "upper_limit";
    const char* key = upper ? "gov.tmax_pu" : "gov.tmin_pu";
    if (lim >= (upper ? up : down)) {
      m.note(
          fmt::format("saturation: {} {:.4g} % lies beyond the recorded input ({:.4g} %); "
                      "{} left unchanged",
                      word, lim, upper ? up : down, key));
      continue;
    }
    m.set(key, rack + (upper ? lim : -lim) * a_r, "saturation",
          fmt::format("rack at the mean bias {:.4g} pu {} {} {:.4g} % x {:.4g} pu/%", rack,
                      upper ? "+" : "-", word, lim, a_r));
  }
}

}  // namespace rig::diagnose::effects
