#include "plantsim/plant/measurement_chain.hpp"

#include <cmath>
#include <numbers>

namespace plantsim {

double MeasurementChain::sample_kw(const Params& p, double t_s, double p_pu, double ripple_pu) {
  double y = p[P::kMeasGain] * (p_pu + ripple_pu) * p[P::kRatedKw] + p[P::kMeasOffset];
  // Both draws happen every tick whatever the amplitudes, so a fault that switches noise on
  // does not shift the random sequence of the other source.
  const double n_white = normal_(rng_);
  const double n_drift = normal_(rng_);
  const double a = drift_decay_(-dt_s_ / p[P::kMeasDriftTau]);
  drift_kw_ = a * drift_kw_ + std::sqrt(1.0 - a * a) * p[P::kMeasDrift] * n_drift;
  y += drift_kw_ + p[P::kMeasNoise] * n_white;
  y += p[P::kMeasPickup] * std::sin(2.0 * std::numbers::pi * p[P::kMeasPickupHz] * t_s);
  const double q = p[P::kMeasQuant];
  if (q > 0.0) y = q * std::round(y / q);
  const double rc = p[P::kMeasAcRc];
  if (rc <= 0.0) return y;
  // High-pass = input - ZOH-exact low-pass: l_k = b l_{k-1} + (1 - b) y_{k-1}, b = exp(-dt/RC).
  if (!ac_started_) {
    ac_lowpass_kw_ = y;
    ac_started_ = true;
  }
  const double out = y - ac_lowpass_kw_;
  const double b = std::exp(-dt_s_ / rc);
  ac_lowpass_kw_ = b * ac_lowpass_kw_ + (1.0 - b) * y;
  return out;
}

}  // namespace plantsim
