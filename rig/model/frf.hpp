// Frequency-response points: the one FRF type of the project (DESIGN.md section 5, FRF csv:
// freq_hz,mag,phase_deg,coherence [,mag_lo,mag_hi] [,valid]). The estimators (swept sine,
// H1) produce it, `rig compare` and the session judge it, rig/model/frf_file.hpp writes and
// reads it without loss, so every reader judges the same points.
#pragma once

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <vector>

namespace rig::model {

struct FrfPoint {
  double freq_hz = 0.0;
  double mag = 0.0;        // |H|, output units per input unit
  double phase_deg = 0.0;  // arg H, wrapped to (-180, 180] unless unwrapped by the caller
  double coherence = 0.0;  // magnitude-squared coherence (H1) or the swept-sine equivalent
  double mag_lo = std::numeric_limits<double>::quiet_NaN();  // ~1-sigma band when known
  double mag_hi = std::numeric_limits<double>::quiet_NaN();
  bool valid = true;  // the estimator's own quality verdict (distortion, noise, back-off)

  std::complex<double> value() const {
    return std::polar(mag, phase_deg * std::numbers::pi / 180.0);
  }
  bool has_band() const { return std::isfinite(mag_lo) && std::isfinite(mag_hi); }
};

using Frf = std::vector<FrfPoint>;

// Wraps an angle to (-180, 180].
inline double wrap_deg(double deg) {
  double w = std::remainder(deg, 360.0);  // in [-180, 180]
  return w <= -180.0 ? w + 360.0 : w;
}

inline double to_db(double mag) { return 20.0 * std::log10(mag); }

// Removes 360-degree jumps between successive points (in frequency order), keeping the
// first point's phase; for plotting a delay as a straight line.
void unwrap_phase_deg(std::vector<FrfPoint>& points);

// The response times e^{-j 2 pi f delay_s}: each phase falls by 360 f delay_s degrees
// (wrapped); magnitudes, bands and verdicts are unchanged. A negative delay advances.
void add_delay(std::vector<FrfPoint>& points, double delay_s);

}  // namespace rig::model
