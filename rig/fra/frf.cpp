#include "rig/fra/frf.hpp"

namespace rig::fra {

void unwrap_phase_deg(std::vector<FrfPoint>& points) {
  for (std::size_t i = 1; i < points.size(); ++i) {
    // Choose the 360-degree branch closest to the previous point.
    const double step = wrap_deg(points[i].phase_deg - points[i - 1].phase_deg);
    points[i].phase_deg = points[i - 1].phase_deg + step;
  }
}

}  // namespace rig::fra
