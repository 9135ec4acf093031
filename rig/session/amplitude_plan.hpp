// Layer 1 of the safety model (DESIGN.md section 8): choose the excitation amplitude so that
// the predicted peak power deviation stays inside plan_fraction (80 %) of the band.
//
// The response to a random excitation of rms e is taken as Gaussian with rms g e, g the rms
// gain (kW rms per % rms) of the plant over the excitation's band. Its peak over a run is
// bounded by k_sigma rms (k = 4: exceeded by a Gaussian with probability 6e-5 per sample),
// and the measured noise adds its own peak, summed rather than root-sum-squared because
// both can peak together:
//     peak = k_sigma (margin g e + noise_rms)  <=  plan_fraction band
//  => e = (plan_fraction band / k_sigma - noise_rms) / (margin g)
// `margin` (>= 1) covers the error of g. The gain comes either from a pilot run,
//     g = sqrt(max(rms_response^2 - rms_noise^2, 0)) / rms_pilot_excitation,
// (the noise, measured in the steady-state check, is uncorrelated with the pilot and adds in
// power), or from a prior model for an excitation flat up to bandwidth B,
//     g^2 = (1/B) integral_0^B |G(j 2 pi f)|^2 df.
// Layer 2 (the supervisor's back-off) catches what an underestimated gain lets through.
#pragma once

#include <functional>
#include <string>

namespace rig::session {

struct PilotEstimate {
  double excitation_rms_pct = 0.0;  // rms of the pilot excitation as applied
  double response_rms_kw = 0.0;     // rms of P - P0 during the pilot (noise included)
  double noise_rms_kw = 0.0;        // rms of P - P0 with no excitation (steady-state check)
};

struct AmplitudePlanOptions {
  double band_kw = 0.0;        // supervisor band, |P - P0| limit
  double plan_fraction = 0.8;  // predicted peak within this fraction of the band
  double k_sigma = 4.0;        // peak-to-rms factor of the response and the noise
  double gain_margin = 1.25;   // >= 1, multiplies the gain estimate
  double max_excitation_rms_pct = 1.0;
};

struct AmplitudePlan {
  bool feasible = false;
  std::string reason;               // why not, one line (empty when feasible)
  double gain_rms = 0.0;            // kW rms per % rms, as used (before the margin)
  double excitation_rms_pct = 0.0;  // planned rms of the excitation
  double predicted_peak_kw = 0.0;   // k_sigma (margin g e + noise_rms)
};

// Gain from a pilot run (see the header comment); throws std::invalid_argument on a
// non-positive pilot excitation or non-finite input.
double pilot_gain_rms(const PilotEstimate& pilot);

// Gain of a prior model for an excitation flat from 0 to bandwidth_hz (trapezoidal rule on
// 2000 intervals). `magnitude` returns |G| in kW per % at a frequency in Hz.
double prior_gain_rms(const std::function<double(double freq_hz)>& magnitude, double bandwidth_hz);

// Plans the excitation rms for the gain and the measured noise rms. Infeasible (not thrown)
// when the noise alone fills the planned band; the pilot phase then refuses to excite.
AmplitudePlan plan_excitation(double gain_rms, double noise_rms_kw,
                              const AmplitudePlanOptions& options);

}  // namespace rig::session
