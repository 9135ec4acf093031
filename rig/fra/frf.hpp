// Frequency-response points, the currency of the FRA layer (DESIGN.md section 5, FRF csv:
// freq_hz,mag,phase_deg,coherence [,mag_lo,mag_hi]).
//
// A model enters the FRA layer as a response callback H(j 2 pi f) so that any model type
// (rig::ident::TransferFunction, a plant linearisation, an analytic test system) can be used
// without this layer depending on it; `as_response_fn` adapts anything with
// `std::complex<double> response(double freq_hz) const`.
#pragma once

#include <cmath>
#include <complex>
#include <concepts>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

namespace rig::fra {

// H(j 2 pi f) of a model, in output units per input unit (kW per % of rated power).
using ResponseFn = std::function<std::complex<double>(double freq_hz)>;

template <class Model>
concept HasResponse = requires(const Model& m, double f) {
  { m.response(f) } -> std::convertible_to<std::complex<double>>;
};

// Wraps a model object; the model must outlive the returned callback.
template <HasResponse Model>
ResponseFn as_response_fn(const Model& model) {
  return [&model](double freq_hz) { return std::complex<double>(model.response(freq_hz)); };
}

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
};

// Wraps an angle to (-180, 180].
inline double wrap_deg(double deg) {
  double w = std::remainder(deg, 360.0);  // in [-180, 180]
  return w <= -180.0 ? w + 360.0 : w;
}

inline double to_db(double mag) { return 20.0 * std::log10(mag); }

// Removes 360-degree jumps between successive points (in frequency order), keeping the
// first point's phase; for plotting a delay as a straight line.
void unwrap_phase_deg(std::vector<FrfPoint>& points);

}  // namespace rig::fra
