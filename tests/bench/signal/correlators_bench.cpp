// Correlator throughput at 256 lags, in ns per input sample, and the online pipeline
// (matched AC coupling of u and y + streaming auto- and cross-correlation, one push per
// 100 Hz tick) as a real-time factor: realtime_x = 10 ms / (time per sample).
// The textbook lag-outer loop is the in-run reference for the ratios.
#include <benchmark/benchmark.h>

#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/correlators.hpp"
#include "rig/signal/excitation.hpp"
#include "rig/signal/streaming_correlator.hpp"

namespace rig::signal {
namespace {

constexpr Eigen::Index kSamples = 1 << 16;
constexpr Eigen::Index kLags = 256;
constexpr double kTickS = 0.01;  // 100 Hz

struct Signals {
  Eigen::VectorXd u, y;
};

const Signals& signals() {
  static const Signals s = [] {
    Signals out;
    out.u = gaussian_excitation({.n = kSamples, .dt_s = kTickS, .bandwidth_hz = 4.0, .seed = 1});
    out.y = 0.7 * out.u +
            gaussian_excitation(
                {.n = kSamples, .dt_s = kTickS, .bandwidth_hz = 20.0, .sigma = 0.3, .seed = 2});
    return out;
  }();
  return s;
}

void per_sample_counters(benchmark::State& state, Eigen::Index samples_per_iteration) {
  const auto samples = static_cast<double>(samples_per_iteration);
  // Seconds per input sample (printed with an SI prefix: "25n" = 25 ns).
  state.counters["s_per_sample"] = benchmark::Counter(
      samples, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  // Seconds of 100 Hz signal handled per second of CPU: the real-time factor (shown as "/s").
  state.counters["realtime_x"] =
      benchmark::Counter(samples * kTickS, benchmark::Counter::kIsIterationInvariantRate);
}

// Reference: r(k) = sum_t y_t u_{t-k}, one dot product per lag (lag-outer loop).
void BM_ReferenceLagLoop(benchmark::State& state) {
  const Signals& s = signals();
  const Eigen::Index z = 102, p = kLags - 1 - z, m = kSamples - kLags + 1;
  Eigen::VectorXd r(kLags);
  for (auto _ : state) {
    for (Eigen::Index i = 0; i < kLags; ++i) {
      const Eigen::Index k = i - z;
      double acc = 0.0;
      for (Eigen::Index t = p; t < p + m; ++t) acc += s.y[t] * s.u[t - k];
      r[i] = acc / static_cast<double>(m);
    }
    benchmark::DoNotOptimize(r.data());
  }
  per_sample_counters(state, kSamples);
}
BENCHMARK(BM_ReferenceLagLoop)->Unit(benchmark::kMillisecond);

void BM_Correlator(benchmark::State& state, CorrelatorKind kind, int skip) {
  const Signals& s = signals();
  const CorrelatorOptions o{.lags = kLags, .skip = skip, .kind = kind, .dt_s = kTickS};
  for (auto _ : state) {
    Correlation c = cross_correlation(s.y, s.u, o);
    benchmark::DoNotOptimize(c.r.data());
  }
  per_sample_counters(state, kSamples);
}
BENCHMARK_CAPTURE(BM_Correlator, direct, CorrelatorKind::kDirect, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Correlator, relay, CorrelatorKind::kRelay, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Correlator, relay_skip8, CorrelatorKind::kRelay, 8)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Correlator, polarity, CorrelatorKind::kPolarity, 1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Correlator, fft, CorrelatorKind::kFft, 1)->Unit(benchmark::kMillisecond);

// The online loop per 100 Hz tick: AC-couple u and y, push one sample into the streaming
// auto+cross correlator (exponential average, 2048-sample blocks).
void BM_StreamingPipeline(benchmark::State& state, CorrelatorKind kind, int skip) {
  const Signals& s = signals();
  AcCoupler couple_u(kTickS, rc_from_corner_hz(0.1)), couple_y(kTickS, rc_from_corner_hz(0.1));
  StreamingCorrelator sc({.correlator = {.lags = kLags, .skip = skip, .kind = kind, .dt_s = kTickS},
                          .averaging = Averaging::kExponential,
                          .weight = 10.0,
                          .block_samples = 2048});
  for (auto _ : state) {
    for (Eigen::Index i = 0; i < kSamples; ++i)
      sc.push(couple_u.step(s.u[i]), couple_y.step(s.y[i]));
    benchmark::DoNotOptimize(sc.products());
  }
  per_sample_counters(state, kSamples);
}
BENCHMARK_CAPTURE(BM_StreamingPipeline, direct, CorrelatorKind::kDirect, 1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_StreamingPipeline, relay, CorrelatorKind::kRelay, 1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_StreamingPipeline, relay_skip8, CorrelatorKind::kRelay, 8)
    ->Unit(benchmark::kMillisecond);

void BM_GaussianExcitation(benchmark::State& state) {
  for (auto _ : state) {
    Eigen::VectorXd x = gaussian_excitation({.n = kSamples, .dt_s = kTickS, .seed = 3});
    benchmark::DoNotOptimize(x.data());
  }
  per_sample_counters(state, kSamples);
}
BENCHMARK(BM_GaussianExcitation)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rig::signal

BENCHMARK_MAIN();
