// Two-sided correlators over finite records (MMFM.md section 5, thesis 3-2).
//
// Estimator. With L = lags, z = zero index (negative lags), P = L - 1 - z (positive lags),
// the lag k (in samples) runs from -z to P, and
//
//     r_yu(k) = 1/N' * sum_{t in T} a(y_t) * b(u_{t-k}),   T = {P, P+s, P+2s, ... <= N-1-z}
//
// i.e. every lag uses the SAME set of anchor samples t (those whose whole lag window lies
// inside the record), so the estimate is unbiased at every lag and N' = |T| =
// ceil((N - L + 1) / s) is the number of products formed per lag. s is Fell's skip: the
// shift runs at the fast rate (lag resolution dt_s) but only every s-th product is formed.
//
//   kDirect    a(y) = y,        b(u) = u           O(N' L) multiply-adds
//   kFft       a(y) = y,        b(u) = u           same estimate computed by FFT (FFTW3)
//   kRelay     a(y) = y,        b(u) = sgn(u)      E = sqrt(2/pi) r_yu / sigma_u (Bussgang,
//                                                  Gaussian u); no multiplications
//   kPolarity  a(y) = sgn(y),   b(u) = sgn(u)      E = (2/pi) asin(rho_yu) (Gaussian);
//                                                  arcsine_correction returns
//                                                  rho = sin(pi/2 * r), a correlation
//                                                  coefficient, not a covariance
//
// sgn(x) = +1 for x >= 0 and -1 for x < 0 (a sign test, as an 8-bit logger would do it).
// auto_correlation(u) is cross_correlation(u, u): for the relay kind that is
// E[u(t) sgn(u(t - tau))], consistent with the cross one so that sqrt(2/pi)/sigma_u cancels
// in H = R_yu / R_uu.
#pragma once

#include <Eigen/Core>

#include "rig/signal/correlation.hpp"

namespace rig::signal {

enum class CorrelatorKind { kDirect, kFft, kRelay, kPolarity };

struct CorrelatorOptions {
  Eigen::Index lags = 256;       // total samples in the two-sided window
  Eigen::Index zero_index = -1;  // -1: automatic (40 % into the window)
  int skip = 1;                  // Fell's skip: form every skip-th product
  CorrelatorKind kind = CorrelatorKind::kDirect;
  bool arcsine_correction = false;  // polarity only
  double dt_s = 0.01;               // sample period = lag resolution
};

// The zero-lag index actually used: options.zero_index, or floor(0.4 * lags) when it is -1.
Eigen::Index resolved_zero_index(const CorrelatorOptions& options);

// Throws std::invalid_argument with a one-line message when options are unusable for a
// record of `samples` samples (samples < 0: length not known yet, as when streaming) (lags < 1,
// zero_index outside the window, skip < 1, dt_s <= 0, lags > samples, arcsine_correction without
// kPolarity).
void validate(const CorrelatorOptions& options, Eigen::Index samples);

// Number of products N' formed per lag for a record of `samples` samples.
Eigen::Index products_per_lag(const CorrelatorOptions& options, Eigen::Index samples);

// r_yu(tau) = E[ y(t) u(t - tau) ] (see the estimator above). y and u must be equally long.
Correlation cross_correlation(const Eigen::VectorXd& y, const Eigen::VectorXd& u,
                              const CorrelatorOptions& options);

// r_uu(tau) = cross_correlation(u, u, options).
Correlation auto_correlation(const Eigen::VectorXd& u, const CorrelatorOptions& options);

const char* to_string(CorrelatorKind kind);

}  // namespace rig::signal
