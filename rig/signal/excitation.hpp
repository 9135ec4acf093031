// Excitation generators (MMFM.md section 8, DESIGN.md section 2). All are deterministic for a
// seed on every platform: they draw from rig::signal::Xoshiro256 (random.hpp), never from
// std:: distributions, whose algorithms differ between standard libraries.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace rig::signal {

// Band-limited Gaussian noise: white N(0,1) -> Butterworth low-pass (order `filter_order`,
// corner `bandwidth_hz`, bilinear with pre-warping) -> mean removed -> scaled so that the
// sample standard deviation (1/n) of the output is exactly `sigma`.
// Spectrum: S(f) ~ sigma^2 |H(f)|^2 with |H(f)|^2 ~ 1 / (1 + (f/fc)^(2 order)) (flat in band,
// -3 dB at fc, -6*order dB/octave above). Autocorrelation: r(tau) = inverse Fourier
// transform of S, i.e. sigma^2 at tau = 0, decaying within about 1/(2 fc) and ringing
// slightly (Butterworth); it is NOT a delta, so correlate long enough (>> 1/fc) records.
// Clipping (clip_sigma > 0): values are limited to +-clip_sigma*sigma and the pre-clip
// scale is solved (bisection) so that the clipped record still has standard deviation sigma.
// Bandwidth: bandwidth_hz, or when it is 0, twice resonance_hz (thesis: "bandwidth about
// twice the resonant frequency"); the defaults give 4 Hz for the ~2 Hz diesel/alternator mode.
struct GaussianOptions {
  Eigen::Index n = 4096;      // samples
  double dt_s = 0.01;         // sample period
  double bandwidth_hz = 0.0;  // low-pass corner (< 0.5/dt_s); 0: 2 * resonance_hz
  double sigma = 1.0;         // output standard deviation (output units)
  double clip_sigma = 0.0;    // clip at +-clip_sigma*sigma; 0 = no clipping (else > 1)
  std::uint64_t seed = 1;
  int filter_order = 4;       // Butterworth order, 1..8
  Eigen::Index warmup = -1;   // filter settling samples discarded; -1: 20 / (fc dt_s)
  double resonance_hz = 2.0;  // expected resonance, used when bandwidth_hz is 0
};
Eigen::VectorXd gaussian_excitation(const GaussianOptions& options);

// Maximal-length PRBS from a Fibonacci LFSR of `register_length` bits (2..31) with the tap set
// of prbs_taps(). Each bit is held for `clock_divider` samples; bit 1 -> +amplitude,
// bit 0 -> -amplitude. The seed picks the (non-zero) starting state, i.e. the phase.
// Period: (2^n - 1) * clock_divider samples. Over one period the mean is amplitude/(2^n-1)
// and, for clock_divider = 1, the circular autocorrelation is two-valued:
//     r(0) = amplitude^2,  r(k) = -amplitude^2 / (2^n - 1) for k != 0 (mod period).
// With divider d it is a triangle of half-width d samples on the same -a^2/(2^n-1) floor.
// Spectrum: lines every 1/(period dt_s) Hz under a sinc^2(f d dt_s) envelope, first null at
// 1/(d dt_s); usable (-3 dB) up to about 0.44/(d dt_s).
struct PrbsOptions {
  Eigen::Index n = 4096;
  int register_length = 10;
  int clock_divider = 1;
  double amplitude = 1.0;
  std::uint64_t seed = 1;
};
Eigen::VectorXd prbs_excitation(const PrbsOptions& options);

// Feedback taps (1-based bit positions, highest first) of a maximal-length LFSR of the given
// length: the polynomial x^n + sum x^tap + 1 is primitive over GF(2) (Xilinx XAPP052 table).
// Throws std::invalid_argument outside 2..31.
std::vector<int> prbs_taps(int register_length);

// Multisine u(t) = sum_k A_k cos(2 pi f_k t + phi_k), t = i dt_s.
// Phases: Schroeder, phi_k = -2 pi sum_{l<k} (k - l) p_l with p_l = A_l^2 / sum A^2 (for equal
// amplitudes phi_k = -pi k (k-1) / K), which keeps the crest factor low (~1.4-1.8 for a flat
// harmonic comb) versus sqrt(2K) for zero phases; or uniform random phases from the seed.
// Spectrum: lines of power A_k^2/2 at f_k. Autocorrelation (periodic record or long
// average): r(tau) = sum_k A_k^2/2 cos(2 pi f_k tau). With rms > 0 the result is scaled to
// that sample rms.
enum class MultisinePhases { kSchroeder, kRandom };
struct MultisineOptions {
  Eigen::Index n = 4096;
  double dt_s = 0.01;
  std::vector<double> frequencies_hz;  // each in (0, 0.5/dt_s)
  std::vector<double> amplitudes;      // empty: all 1; else same length as frequencies_hz
  MultisinePhases phases = MultisinePhases::kSchroeder;
  std::uint64_t seed = 1;  // for kRandom
  double rms = 0.0;        // > 0: scale output to this sample rms
};
Eigen::VectorXd multisine_excitation(const MultisineOptions& options);

// Frequencies k * f0 for k = first..last with f0 = 1/(n dt_s), i.e. a harmonic comb that is
// periodic in the record (no leakage).
std::vector<double> harmonic_frequencies_hz(Eigen::Index n, double dt_s, int first, int last);

// max|x| / rms(x) (rms about zero). Throws std::invalid_argument for an all-zero record.
double crest_factor(const Eigen::VectorXd& x);

}  // namespace rig::signal
