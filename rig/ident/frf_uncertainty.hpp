// How well a model's frequency response is known, from the estimator's asymptotic theory
// (Ljung, System Identification, 2nd ed., sections 9.4 and 9.6; Pintelon and Schoukens,
// System Identification: A Frequency Domain Approach, chapter 7).
//
// The time-domain output error (output_error.hpp) is, by Parseval, a frequency-domain fit
// of G to the raw response Phi_yu / Phi_uu with the weight W = Phi_u; the correlation-domain
// output error of the MMFM refinement (|r_yu - g * r_uu|^2) has W = Phi_u^2 in the limit of
// a long lag window. (With the short windows of the online loop it is 1.3-2 times less
// precise than this formula says; the time-domain output error meets it within 20 %:
// tests/unit/ident/frf_uncertainty_test.cpp.) The raw response at frequency w
// carries the variance Phi_v(w) / (N Phi_u(w)) from noise of spectrum Phi_v. A weighted
// least-squares fit then has the asymptotic (large-N) covariance of the sandwich form
//     P = (1/N) H^-1 S H^-1,
//     H = avg_w W Re(psi psi^H),   S = avg_w W^2 (Phi_v / Phi_u) Re(psi psi^H),
// with psi = dG(jw)/dtheta and avg_w the mean over the frequency circle. For W = Phi_u and
// white noise this is the Cramer-Rao bound sigma^2 (E psi psi^T)^-1 / N (crlb.hpp).
// theta = [a_{n-1}..a_0, b_m..b_0, Td] of the monic model (Td only when it is estimated).
//
// The spectra are smoothed autocorrelation spectra (Parzen lag window, which keeps every
// estimate non-negative) of the excitation and of the output residual v = y - G u of the
// model itself. A model error therefore counts as noise and widens the band, which is the
// safe side. (Phi_yy - |Phi_yu|^2 / Phi_uu needs no model but, smoothed over a lag window,
// overstates the noise several times near a lightly damped resonance.)
//
// The frequency response's band follows by the delta method:
//     d(dB)/dtheta = (20 / ln 10) Re(psi / G),   d(deg)/dtheta = (180 / pi) Im(psi / G).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "rig/model/transfer_function.hpp"
#include "rig/signal/correlation.hpp"

namespace rig::ident {

// Spectral densities on the grid f_k = k / (fft_length dt_s), k = 0 .. fft_length/2, in
// signal units^2 per sample (two-sided: Phi(w) = sum_tau r(tau) e^{-j w tau}).
struct InputNoiseSpectra {
  double dt_s = 0.0;
  int fft_length = 0;
  Eigen::VectorXd freq_hz;
  Eigen::VectorXd phi_u;  // excitation
  Eigen::VectorXd phi_v;  // output noise (not coherent with the excitation)
};

// From the excitation u and the output y of one record and the model: lag window of
// +-half_width samples. Throws std::invalid_argument for unequal lengths, a record shorter
// than two windows, fft_length < 2 half_width or an improper model.
InputNoiseSpectra input_noise_spectra(const Eigen::VectorXd& u, const Eigen::VectorXd& y,
                                      double dt_s, const model::TransferFunction& model,
                                      int half_width = 256, int fft_length = 1024);

// The estimator's criterion weight W = Phi_u^power: 1 for the time-domain output error,
// 2 for the correlation-domain output error.
inline constexpr double kCorrelationDomainWeightPower = 2.0;
inline constexpr double kTimeDomainWeightPower = 1.0;

// Asymptotic covariance of theta (see above) after `samples` samples. Throws
// std::invalid_argument for an improper model or samples <= 0; a singular H gives a matrix
// of infinities (the data do not determine the parameters).
Eigen::MatrixXd asymptotic_covariance(const model::TransferFunction& model,
                                      const InputNoiseSpectra& spectra, double samples,
                                      bool delay_estimated,
                                      double weight_power = kTimeDomainWeightPower);

// d G(j 2 pi f) / d theta for the monic model (theta as above).
Eigen::VectorXcd response_gradient(const model::TransferFunction& model, double freq_hz,
                                   bool delay_estimated);

struct FrfUncertainty {
  double freq_hz = 0.0;
  double mag_db = 0.0;
  double phase_deg = 0.0;
  double sd_db = 0.0;   // one standard deviation of 20 log10 |G|
  double sd_deg = 0.0;  // one standard deviation of arg G
};

// The model's response with its standard deviations at each frequency; cov is
// asymptotic_covariance()'s (same delay_estimated).
std::vector<FrfUncertainty> frf_uncertainty(const model::TransferFunction& model,
                                            const Eigen::MatrixXd& cov,
                                            const std::vector<double>& freqs_hz,
                                            bool delay_estimated);

// The factor c of a SIMULTANEOUS 95 % band over the points: with probability 0.95 the
// estimate's error is within c standard deviations at every point, in magnitude and in
// phase at once (c > 1.96, the pointwise value, because the band must hold everywhere).
// The 95th percentile of max_i max(|e_db,i| / sd_db,i, |e_deg,i| / sd_deg,i) over
// kSimultaneousDraws draws of theta ~ N(0, cov) (a fixed seed: the same inputs give the same
// factor). Returns infinity when cov is not finite.
inline constexpr int kSimultaneousDraws = 2000;
double simultaneous_factor95(const model::TransferFunction& model, const Eigen::MatrixXd& cov,
                             const std::vector<double>& freqs_hz, bool delay_estimated);

// The widest half-band (factor standard deviations) over the points.
struct BandWidth95 {
  double db = 0.0;
  double deg = 0.0;
};
BandWidth95 worst_band95(const std::vector<FrfUncertainty>& points,
                         double factor = 1.959963984540054);

// n log-spaced frequencies from f0 to f1 (n >= 2).
std::vector<double> log_frequencies_hz(double f0_hz, double f1_hz, int n);

}  // namespace rig::ident
