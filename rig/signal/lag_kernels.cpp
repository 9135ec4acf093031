#include "rig/signal/lag_kernels.hpp"

#include <bit>

// On x86-64 each kernel is also compiled for x86-64-v3 (AVX2 + FMA) and picked at load time;
// the baseline build (SSE2) remains for older machines.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define RIG_HOT_LOOP __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define RIG_HOT_LOOP
#endif

namespace rig::signal::detail {

RIG_HOT_LOOP void direct_run(const double* a, const double* w, AnchorRun run,
                             double* __restrict acc) {
  for (Eigen::Index i = 0; i < run.count; ++i) {
    const double at = a[i * run.stride];
    const double* __restrict wi = w + i * run.stride;
    for (Eigen::Index j = 0; j < run.lags; ++j) acc[j] += at * wi[j];
  }
}

RIG_HOT_LOOP void direct_run2(const double* a1, const double* a2, const double* w,
                              AnchorRun run, double* __restrict acc1,
                              double* __restrict acc2) {
  for (Eigen::Index i = 0; i < run.count; ++i) {
    const double at1 = a1[i * run.stride];
    const double at2 = a2[i * run.stride];
    const double* __restrict wi = w + i * run.stride;
    for (Eigen::Index j = 0; j < run.lags; ++j) {
      acc1[j] += at1 * wi[j];
      acc2[j] += at2 * wi[j];
    }
  }
}

RIG_HOT_LOOP void relay_run(const double* a, const std::uint64_t* w_mask, AnchorRun run,
                            double* __restrict acc) {
  for (Eigen::Index i = 0; i < run.count; ++i) {
    const auto bits = std::bit_cast<std::uint64_t>(a[i * run.stride]);
    const std::uint64_t* __restrict mi = w_mask + i * run.stride;
    for (Eigen::Index j = 0; j < run.lags; ++j) acc[j] += std::bit_cast<double>(bits ^ mi[j]);
  }
}

RIG_HOT_LOOP void relay_run2(const double* a1, const double* a2, const std::uint64_t* w_mask,
                             AnchorRun run, double* __restrict acc1,
                             double* __restrict acc2) {
  for (Eigen::Index i = 0; i < run.count; ++i) {
    const auto bits1 = std::bit_cast<std::uint64_t>(a1[i * run.stride]);
    const auto bits2 = std::bit_cast<std::uint64_t>(a2[i * run.stride]);
    const std::uint64_t* __restrict mi = w_mask + i * run.stride;
    for (Eigen::Index j = 0; j < run.lags; ++j) {
      acc1[j] += std::bit_cast<double>(bits1 ^ mi[j]);
      acc2[j] += std::bit_cast<double>(bits2 ^ mi[j]);
    }
  }
}

RIG_HOT_LOOP void polarity_run(const std::uint8_t* a_neg, const std::uint8_t* w_neg,
                               AnchorRun run, std::int64_t* __restrict disagree) {
  for (Eigen::Index i = 0; i < run.count; ++i) {
    const std::uint8_t at = a_neg[i * run.stride];
    const std::uint8_t* __restrict wi = w_neg + i * run.stride;
    for (Eigen::Index j = 0; j < run.lags; ++j) disagree[j] += at ^ wi[j];
  }
}

}  // namespace rig::signal::detail
