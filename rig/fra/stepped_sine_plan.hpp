// Stepped-sine plan: which frequencies, how long at each, and how large.
//
// Grid: `points` frequencies log-spaced from f_start_hz to f_stop_hz (default 0.2-10 Hz, 20).
//
// Timing rule per point at frequency f (all rounded up to whole cycles, then to samples):
//   settle    = max(settle_time_constants * slowest_time_constant_s, min_settle_cycles / f)
//               With the default 5 time constants the start-up transient of the slowest
//               expected mode has decayed to e^-5 < 0.7 % before integration starts.
//               For the Stornoway mode (2 Hz, zeta 0.1) tau = 1 / (zeta w_n) = 0.8 s.
//   integrate = max(min_integrate_cycles, min_integrate_s * f) cycles: whole cycles so the
//               lock-in projection is unbiased; at least min_integrate_s of data so that the
//               noise in the lock-in's bandwidth 1/T stays small at high frequencies.
//               Noise rule (when noise_rms_kw and target_rel_std are > 0): white noise of rms
//               sigma on N samples gives the response phasor Y a relative standard error
//               r = sqrt(2 sigma^2 / N) / |Y| (in magnitude, and in phase in radians), so with
//               the predicted |Y| = A |G(f)| the integration lasts at least
//                 N dt = 2 sigma^2 dt / (target_rel_std^2 (A |G(f)|)^2)   (<= max_integrate_s).
//               It lengthens the points whose amplitude is capped below the band (high f).
//   A raised-cosine fade-in over the first ramp_cycles (inside the settle time) avoids a step
//   in the excitation's slope and the large start-up transient a resonance would give.
//
// Amplitude rule: the steady response to A sin(w t) has peak A |G(f)|, so with the prior
// model G (kW per % of rated power) the amplitude is
//   A(f) = min(max_amplitude_pct,
//              (plan_fraction * band_kw - noise_peak_kw) / (prior_margin * G_max(f)))
// where G_max(f) is the largest prior gain within +-prior_spread of f (a prior whose
// resonance sits slightly off still gets a safe amplitude) and prior_margin covers the prior's
// gain error and the fade-in transient. The supervisor's back-off and trip remain in force.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "rig/fra/frf.hpp"

namespace rig::fra {

struct AmplitudeLimits {
  double band_kw = 0.0;            // supervisor band, |P - P0| limit (e.g. 3 % of P0)
  double plan_fraction = 0.8;      // predicted peak within this fraction of the band
  double noise_peak_kw = 0.0;      // peak |P - P0| without excitation (steady-state check)
  double prior_margin = 1.5;       // >= 1: divides the amplitude
  double prior_spread = 0.15;      // relative frequency neighbourhood searched for G_max
  double max_amplitude_pct = 1.0;  // never more than this, whatever the prior says
};

struct SweepPlanOptions {
  double f_start_hz = 0.2;
  double f_stop_hz = 10.0;
  int points = 20;
  double dt_s = 0.01;                    // tick of the session loop
  double slowest_time_constant_s = 0.8;  // of the expected dynamics
  double settle_time_constants = 5.0;
  int min_settle_cycles = 3;
  int min_integrate_cycles = 8;
  double min_integrate_s = 4.0;
  double ramp_cycles = 1.0;  // fade-in, must not exceed the settle cycles
  double noise_rms_kw = 0.0;     // white noise on the response; 0 disables the noise rule
  double target_rel_std = 0.0;   // lock-in relative standard error aimed at; 0 disables it
  double max_integrate_s = 0.0;  // cap of the noise rule; 0: no cap
  AmplitudeLimits amplitude;
};

struct SweepPoint {
  double freq_hz = 0.0;
  double amplitude_pct = 0.0;      // excitation amplitude, % of rated power
  double predicted_peak_kw = 0.0;  // amplitude * prior gain at f + noise peak
  int settle_cycles = 0;
  int integrate_cycles = 0;
  Eigen::Index settle_samples = 0;
  Eigen::Index integrate_samples = 0;
  Eigen::Index ramp_samples = 0;

  Eigen::Index total_samples() const { return settle_samples + integrate_samples; }
};

struct SweepPlan {
  double dt_s = 0.01;
  std::vector<SweepPoint> points;

  Eigen::Index total_samples() const;
  double duration_s() const { return static_cast<double>(total_samples()) * dt_s; }
};

// Log-spaced frequencies, both ends included (points >= 2, or 1 giving f_start_hz).
std::vector<double> log_grid_hz(double f_start_hz, double f_stop_hz, int points);

// The amplitude rule above at one frequency; throws std::invalid_argument when the band
// cannot hold even the noise (plan_fraction * band_kw <= noise_peak_kw) or inputs are bad.
double sine_amplitude_pct(const ResponseFn& prior, double freq_hz, const AmplitudeLimits& limits);

// Builds the plan; throws std::invalid_argument naming the bad field (f_stop_hz at or above
// 0.4 / dt_s, points < 1, a missing prior, ...).
SweepPlan make_sweep_plan(const SweepPlanOptions& options, const ResponseFn& prior);

}  // namespace rig::fra
