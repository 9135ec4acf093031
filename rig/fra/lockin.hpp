// Lock-in (correlation) demodulation of a stepped-sine record.
//
// Over an integration window of whole cycles the signal is projected on
//   x(t) ~ c0 + c1 (t - t_mid) + sum_{k=1..K} [a_k cos(k w t) + b_k sin(k w t)]
// by least squares. Over whole cycles of a uniformly sampled sine this is the classic
// lock-in correlation X_k = (2/N) sum x(t) e^{-j k w t}; the least-squares form stays exact
// when the cycle does not hold a whole number of samples, and the c1 term keeps slow power
// drift (island load wander) out of the fundamental. The complex amplitude follows
//   x(t) = Re{ X_k e^{j k w t} },  X_k = a_k - j b_k,
// so the frequency response at w is the ratio H = Y_1 / U_1 of response and excitation.
//
// Quality figures:
//   distortion = sum_{k=2..K} |X_k|^2 / |X_1|^2          (harmonic power vs fundamental)
//   noise      = residual variance / (|X_1|^2 / 2)        (broadband noise-to-signal)
//   rel_var    = E|dX_1|^2 / |X_1|^2 = 4 s^2 / (N |X_1|^2)  (s^2: residual variance), the
//                variance of the fundamental's estimate (each of a_1, b_1 has 2 s^2 / N).
//   coherence  = 1 / ((1 + rel_var_u)(1 + rel_var_y)): the fraction of the power in the
//                lock-in's resolution bandwidth 1/T that is coherent with the excitation,
//                the swept-sine counterpart of the magnitude-squared coherence of H1.
#pragma once

#include <Eigen/Core>
#include <complex>
#include <vector>

namespace rig::fra {

struct HarmonicFit {
  std::vector<std::complex<double>> harmonics;  // X_1 .. X_K (K may be cut below Nyquist)
  double mean = 0.0;                            // c0
  double drift_per_s = 0.0;                     // c1
  double residual_var = 0.0;                    // variance left after the fit
  Eigen::Index samples = 0;

  std::complex<double> fundamental() const { return harmonics.front(); }
  double fundamental_power() const;  // |X_1|^2 / 2
  double distortion() const;         // harmonic power / fundamental power
  double noise_ratio() const;        // residual variance / fundamental power
  double relative_variance() const;  // E|dX_1|^2 / |X_1|^2
};

// Fits the record x (sample i at t0_s + i dt_s) at the fundamental freq_hz and its
// harmonics 2..max_harmonic (those below 0.45 / dt_s). Needs at least 4 K + 4 samples.
HarmonicFit fit_harmonics(const Eigen::VectorXd& x, double freq_hz, double dt_s, double t0_s = 0.0,
                          int max_harmonic = 5);

struct LockInPoint {
  double freq_hz = 0.0;
  std::complex<double> ratio;  // Y_1 / U_1
  HarmonicFit u, y;
  double coherence = 0.0;      // see the header comment
  double mag_std_db = 0.0;     // ~1-sigma, from rel_var: 20 log10(e) sqrt((rv_u + rv_y) / 2)
  double phase_std_deg = 0.0;  // ~1-sigma: sqrt((rv_u + rv_y) / 2) rad
};

LockInPoint lock_in(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double freq_hz, double dt_s,
                    double t0_s = 0.0, int max_harmonic = 5);

}  // namespace rig::fra
