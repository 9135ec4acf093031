// Inner loops shared by the batch and streaming correlators (internal to rig/signal).
//
// A run is `count` anchors spaced `stride` samples apart (Fell's skip). For anchor i the
// anchor value is a[i*stride] and the lag window is w[i*stride .. i*stride + lags), so
//     acc[j] += a[i*stride] * w[i*stride + j]      (j = P - k, reverse lag order)
// The window is contiguous, the loop over j is unit-stride and the accumulator (lags
// doubles) stays in L1: the compiler vectorises it. Relay replaces the product by a
// sign-bit XOR (y * sgn(u) = y with its sign flipped where u < 0); polarity counts sign
// disagreements, r = 1 - 2 disagreements / N'.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace rig::signal::detail {

struct AnchorRun {
  Eigen::Index count = 0;   // anchors
  Eigen::Index stride = 1;  // skip
  Eigen::Index lags = 0;    // window length L
};

constexpr std::uint64_t kSignBit = 0x8000000000000000ULL;
inline std::uint64_t sign_mask(double x) { return x < 0.0 ? kSignBit : 0ULL; }
inline std::uint8_t is_negative(double x) { return x < 0.0 ? 1 : 0; }

void direct_run(const double* a, const double* w, AnchorRun run, double* acc);
void direct_run2(const double* a1, const double* a2, const double* w, AnchorRun run, double* acc1,
                 double* acc2);
void relay_run(const double* a, const std::uint64_t* w_mask, AnchorRun run, double* acc);
void relay_run2(const double* a1, const double* a2, const std::uint64_t* w_mask, AnchorRun run,
                double* acc1, double* acc2);
void polarity_run(const std::uint8_t* a_neg, const std::uint8_t* w_neg, AnchorRun run,
                  std::int64_t* disagree);
// Same sums as direct_run, by one real FFT of the run's segment (FFTW3, thread-safe).
void fft_run(const double* a, const double* w, AnchorRun run, double* acc);

}  // namespace rig::signal::detail
