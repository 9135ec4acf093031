#include "rig/signal/lag_kernels.hpp"

#include <bit>

// On x86-64 each kernel is also compiled for x86-64-v3 (AVX2 + FMA) and picked at load time;
// the baseline build (SSE2) remains for older machines.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define RIG_HOT_LOOP __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define RIG_HOT_LOOP
#endif

// The loops are limited by loading and storing the accumulator, not by arithmetic, so four
// anchors are folded into each pass over it (register blocking):
//     acc[j] += a0 w0[j] + a1 w1[j] + a2 w2[j] + a3 w3[j]
// which reads and writes acc once per four anchors instead of once per anchor.

namespace rig::signal::detail {
namespace {

inline double flip(std::uint64_t bits, std::uint64_t mask) {
  return std::bit_cast<double>(bits ^ mask);  // y * sgn(u) without a multiplication
}

}  // namespace

RIG_HOT_LOOP void direct_run(const double* a, const double* w, AnchorRun run,
                             double* __restrict acc) {
  const Eigen::Index s = run.stride, lags = run.lags;
  Eigen::Index i = 0;
  for (; i + 4 <= run.count; i += 4) {
    const double a0 = a[i * s], a1 = a[(i + 1) * s], a2 = a[(i + 2) * s], a3 = a[(i + 3) * s];
    const double* __restrict w0 = w + i * s;
    const double* __restrict w1 = w0 + s;
    const double* __restrict w2 = w1 + s;
    const double* __restrict w3 = w2 + s;
    for (Eigen::Index j = 0; j < lags; ++j) {
      acc[j] += (a0 * w0[j] + a1 * w1[j]) + (a2 * w2[j] + a3 * w3[j]);
    }
  }
  for (; i < run.count; ++i) {
    const double at = a[i * s];
    const double* __restrict wi = w + i * s;
    for (Eigen::Index j = 0; j < lags; ++j) acc[j] += at * wi[j];
  }
}

RIG_HOT_LOOP void direct_run2(const double* a1, const double* a2, const double* w, AnchorRun run,
                              double* __restrict acc1, double* __restrict acc2) {
  const Eigen::Index s = run.stride, lags = run.lags;
  Eigen::Index i = 0;
  for (; i + 4 <= run.count; i += 4) {
    const double p0 = a1[i * s], p1 = a1[(i + 1) * s], p2 = a1[(i + 2) * s], p3 = a1[(i + 3) * s];
    const double q0 = a2[i * s], q1 = a2[(i + 1) * s], q2 = a2[(i + 2) * s], q3 = a2[(i + 3) * s];
    const double* __restrict w0 = w + i * s;
    const double* __restrict w1 = w0 + s;
    const double* __restrict w2 = w1 + s;
    const double* __restrict w3 = w2 + s;
    for (Eigen::Index j = 0; j < lags; ++j) {
      acc1[j] += (p0 * w0[j] + p1 * w1[j]) + (p2 * w2[j] + p3 * w3[j]);
      acc2[j] += (q0 * w0[j] + q1 * w1[j]) + (q2 * w2[j] + q3 * w3[j]);
    }
  }
  for (; i < run.count; ++i) {
    const double p = a1[i * s], q = a2[i * s];
    const double* __restrict wi = w + i * s;
    for (Eigen::Index j = 0; j < lags; ++j) {
      acc1[j] += p * wi[j];
      acc2[j] += q * wi[j];
    }
  }
}

RIG_HOT_LOOP void relay_run(const double* a, const std::uint64_t* w_mask, AnchorRun run,
                            double* __restrict acc) {
  const Eigen::Index s = run.stride, lags = run.lags;
  Eigen::Index i = 0;
  for (; i + 4 <= run.count; i += 4) {
    const auto b0 = std::bit_cast<std::uint64_t>(a[i * s]);
    const auto b1 = std::bit_cast<std::uint64_t>(a[(i + 1) * s]);
    const auto b2 = std::bit_cast<std::uint64_t>(a[(i + 2) * s]);
    const auto b3 = std::bit_cast<std::uint64_t>(a[(i + 3) * s]);
    const std::uint64_t* __restrict m0 = w_mask + i * s;
    const std::uint64_t* __restrict m1 = m0 + s;
    const std::uint64_t* __restrict m2 = m1 + s;
    const std::uint64_t* __restrict m3 = m2 + s;
    for (Eigen::Index j = 0; j < lags; ++j) {
      acc[j] += (flip(b0, m0[j]) + flip(b1, m1[j])) + (flip(b2, m2[j]) + flip(b3, m3[j]));
    }
  }
  for (; i < run.count; ++i) {
    const auto bits = std::bit_cast<std::uint64_t>(a[i * s]);
    const std::uint64_t* __restrict mi = w_mask + i * s;
    for (Eigen::Index j = 0; j < lags; ++j) acc[j] += flip(bits, mi[j]);
  }
}

RIG_HOT_LOOP void relay_run2(const double* a1, const double* a2, const std::uint64_t* w_mask,
                             AnchorRun run, double* __restrict acc1, double* __restrict acc2) {
  const Eigen::Index s = run.stride, lags = run.lags;
  auto bits = [](const double* a, Eigen::Index i) { return std::bit_cast<std::uint64_t>(a[i]); };
  Eigen::Index i = 0;
  for (; i + 4 <= run.count; i += 4) {
    const std::uint64_t p0 = bits(a1, i * s), p1 = bits(a1, (i + 1) * s);
    const std::uint64_t p2 = bits(a1, (i + 2) * s), p3 = bits(a1, (i + 3) * s);
    const std::uint64_t q0 = bits(a2, i * s), q1 = bits(a2, (i + 1) * s);
    const std::uint64_t q2 = bits(a2, (i + 2) * s), q3 = bits(a2, (i + 3) * s);
    const std::uint64_t* __restrict m0 = w_mask + i * s;
    const std::uint64_t* __restrict m1 = m0 + s;
    const std::uint64_t* __restrict m2 = m1 + s;
    const std::uint64_t* __restrict m3 = m2 + s;
    for (Eigen::Index j = 0; j < lags; ++j) {
      acc1[j] += (flip(p0, m0[j]) + flip(p1, m1[j])) + (flip(p2, m2[j]) + flip(p3, m3[j]));
      acc2[j] += (flip(q0, m0[j]) + flip(q1, m1[j])) + (flip(q2, m2[j]) + flip(q3, m3[j]));
    }
  }
  for (; i < run.count; ++i) {
    const std::uint64_t p = bits(a1, i * s), q = bits(a2, i * s);
    const std::uint64_t* __restrict mi = w_mask + i * s;
    for (Eigen::Index j = 0; j < lags; ++j) {
      acc1[j] += flip(p, mi[j]);
      acc2[j] += flip(q, mi[j]);
    }
  }
}

RIG_HOT_LOOP void polarity_run(const std::uint8_t* a_neg, const std::uint8_t* w_neg, AnchorRun run,
                               std::int64_t* __restrict disagree) {
  const Eigen::Index s = run.stride, lags = run.lags;
  Eigen::Index i = 0;
  for (; i + 4 <= run.count; i += 4) {
    const std::uint8_t n0 = a_neg[i * s], n1 = a_neg[(i + 1) * s];
    const std::uint8_t n2 = a_neg[(i + 2) * s], n3 = a_neg[(i + 3) * s];
    const std::uint8_t* __restrict w0 = w_neg + i * s;
    const std::uint8_t* __restrict w1 = w0 + s;
    const std::uint8_t* __restrict w2 = w1 + s;
    const std::uint8_t* __restrict w3 = w2 + s;
    for (Eigen::Index j = 0; j < lags; ++j) {
      disagree[j] +=
          static_cast<std::uint8_t>((n0 ^ w0[j]) + (n1 ^ w1[j]) + (n2 ^ w2[j]) + (n3 ^ w3[j]));
    }
  }
  for (; i < run.count; ++i) {
    const std::uint8_t at = a_neg[i * s];
    const std::uint8_t* __restrict wi = w_neg + i * s;
    for (Eigen::Index j = 0; j < lags; ++j) disagree[j] += at ^ wi[j];
  }
}

}  // namespace rig::signal::detail
