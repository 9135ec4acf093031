// Starting points of the hypothesis fits. Each comes from the location step where it can
// (phase slope for a dead time, phase lag for a lag, the |H1/G| peak for a resonance, the
// spectral line for a periodic disturbance) and otherwise from the data's scales.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

std::vector<std::vector<double>> seeds_for(Effect e, const Problem& pr, const Location& loc) {
  const DataScales& s = pr.scales;
  const FrequencyLocation& f = loc.freq;
  const double su = s.u_std;
  switch (e) {
    case Effect::kDeadTime:
      return {{f.delay_from_phase_s}, {0.5 * f.delay_from_phase_s + 0.01}};
    case Effect::kExtraLag:
    case Effect::kSensorLag:
      return {{f.lag_from_phase_s > 0.0 ? f.lag_from_phase_s : 0.05}, {5.0 * s.dt_s}};
    case Effect::kResonance: {
      const double fr = f.peak_ratio_freq_hz > 0.0 ? f.peak_ratio_freq_hz : 0.25 * f.input_band_hz;
      const double band_mid =
          f.band_hz ? std::sqrt(std::max(f.band_hz->first, 1e-3) * f.band_hz->second) : fr;
      return {{fr, 0.05, f.peak_ratio}, {band_mid, 0.1, 1.5}};
    }
    case Effect::kAcCoupling:
      return {{5.0}, {30.0}};
    case Effect::kDeadband:
    case Effect::kBacklash:
      return {{0.1 * su}, {0.4 * su}};
    case Effect::kSaturation:
      return {
          {1.5 * su, 1.5 * su, s.dt_s}, {2.5 * su, 2.5 * su, s.dt_s}, {1.5 * su, 2.0 * su, 3.0}};
    case Effect::kRateLimit:
      return {
          {0.5 * s.u_rate_std, s.dt_s}, {1.5 * s.u_rate_std, s.dt_s}, {1.5 * s.u_rate_std, 3.0}};
    case Effect::kStaticNonlinearity:
      return {{0.0, 0.0}, {0.1, -0.05}};
    case Effect::kNonlinearStiffness: {
      // The cubic term at the peak is (peak/sd)^2 times its value at 1 sd: an output with a
      // high crest factor (an arrow, pulses) makes +-0.1 unstable at its peaks (Silverbox
      // arrow, crest 5.6: +-0.03 already diverges); start at 0.1 (sd/peak)^2 there as well.
      if (s.z_peak_ratio <= 4.0) return {{0.1}, {-0.1}};
      const double c = 0.1 / (s.z_peak_ratio * s.z_peak_ratio);
      return {{0.1}, {-0.1}, {c}, {-c}};
    }
    case Effect::kCoulombFriction:
      return {{0.05 * su}, {0.2 * su}};
    case Effect::kLoadDamping: {
      const auto mode = dominant_mode(pr.tf);
      const double z = mode ? mode->second : 0.1;
      return {{z * 0.6}, {z * 1.6}};
    }
    case Effect::kGainChange:
      return {{f.gain_ratio}};
    case Effect::kPeriodicDisturbance:
      return {{loc.dist.line_freq_hz}};
    case Effect::kDrift:
      return {{loc.dist.drift_tau_s}};
  }
  return {};
}

}  // namespace rig::diagnose
