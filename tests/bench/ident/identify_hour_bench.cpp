// Whole-record identify() on one hour of 100 Hz data (360,000 samples): the Stornoway-like
// second-order-plus-delay loop e^{-0.06 s} / (0.07 s^2 + 0.19 s + 11.05), Gaussian excitation
// of 4 Hz bandwidth, SNR 0 dB, seed 1. Wall-clock time; the counter rt_factor is record
// seconds processed per wall second (3600 s / time per call). The reference in the same run
// is one lsim of the same record through the true plant, so "identify / lsim" compares across
// machines.
#include <benchmark/benchmark.h>

#include "rig/ident/identify.hpp"
#include "tests/bench/ident/ident_experiments.hpp"

namespace rig::ident {
namespace {

constexpr double kMinutes = 60.0;

const experiments::Record& hour() {
  static const experiments::Record r = experiments::stornoway_record(1, kMinutes);
  return r;
}

void report(benchmark::State& state, const IdentifyResult* res) {
  state.counters["rt_factor"] =
      benchmark::Counter(kMinutes * 60.0, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["samples"] = static_cast<double>(hour().u.size());
  if (res) {
    state.counters["fn_hz"] = res->derived.fn_hz;
    state.counters["zeta"] = res->derived.zeta;
    state.counters["delay_s"] = res->delay_s;
    state.counters["order_n"] = res->order.n;
  }
}

// Times identify() on the hour-long record (generated outside the timed loop) and reports
// the estimate and the real-time factor.
void time_identify(benchmark::State& state, const IdentifyOptions& io) {
  const experiments::Record& rec = hour();
  IdentifyResult res;
  for (auto _ : state) {
    res = identify(rec.u, rec.y, rec.dt_s, io);
    benchmark::DoNotOptimize(res);
  }
  report(state, &res);
}

// Defaults of `rig identify`: order chosen from the nine candidates, delay estimated,
// block-spread standard errors over 8 blocks.
void BM_IdentifyHourAutoOrder(benchmark::State& state) { time_identify(state, IdentifyOptions{}); }
BENCHMARK(BM_IdentifyHourAutoOrder)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(2);

// Order given (n = 2, m = 0): correlation, delay search, MMFM and block standard errors only.
void BM_IdentifyHourOrder2(benchmark::State& state) {
  IdentifyOptions io;
  io.order = model::ModelOrder{2, 0};
  time_identify(state, io);
}
BENCHMARK(BM_IdentifyHourOrder2)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(2);

void BM_LsimHourReference(benchmark::State& state) {
  const model::TransferFunction tf = experiments::stornoway_tf();
  const experiments::Record& rec = hour();
  for (auto _ : state) benchmark::DoNotOptimize(simulate(tf, rec.u, rec.dt_s));
  report(state, nullptr);
}
BENCHMARK(BM_LsimHourReference)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace rig::ident

BENCHMARK_MAIN();
