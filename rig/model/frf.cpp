#include "rig/model/frf.hpp"

namespace rig::model {

void unwrap_phase_deg(std::vector<FrfPoint>& points) {
  for (std::size_t i = 1; i < points.size(); ++i) {
    // Choose the 360-degree branch closest to the previous point.
    const double step = wrap_deg(points[i].phase_deg - points[i - 1].phase_deg);
    points[i].phase_deg = points[i - 1].phase_deg + step;
  }
}

void add_delay(std::vector<FrfPoint>& points, double delay_s) {
  for (auto& p : points) p.phase_deg = wrap_deg(p.phase_deg - 360.0 * p.freq_hz * delay_s);
}

}  // namespace rig::model
