// The governor's scales the input nonlinearities map through (common.hpp gives the
// derivation).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

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

}  // namespace rig::diagnose::effects
