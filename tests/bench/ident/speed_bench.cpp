// Speed of the estimators. The reference in the same run is one lsim of the same lag axis,
// so the ratio "MMFM solve / lsim" is comparable across machines.
#include <benchmark/benchmark.h>

#include "rig/ident/mmfm.hpp"
#include "rig/ident/srivc.hpp"
#include "tests/bench/ident/ident_experiments.hpp"
#include "tests/unit/ident/analytic_correlations.hpp"

namespace rig::ident {
namespace {

const testing::CorrelationPair& pair() {
  static const testing::CorrelationPair p = testing::triangle_pair(
      testing::make_tf({1.0}, {0.07, 0.19, 11.05}, 0.06), 0.02, 0.01, 256, 102);
  return p;
}

MmfmSettings settings_8() {
  MmfmSettings st;
  st.functions = 8;
  st.scale_s = 0.08;
  st.centres_s = admissible_centres(pair().ruu, pair().ryu, {2, 0}, 0.06, 0.06, st, 1);
  return st;
}

void BM_MmfmSolve8Functions(benchmark::State& state) {
  const MmfmSettings st = settings_8();
  for (auto _ : state)
    benchmark::DoNotOptimize(mmfm_solve(pair().ruu, pair().ryu, {2, 0}, 0.06, st));
}
BENCHMARK(BM_MmfmSolve8Functions);

void BM_LsimReference256(benchmark::State& state) {
  const model::TransferFunction tf = testing::make_tf({1.0}, {0.07, 0.19, 11.05}, 0.06);
  for (auto _ : state) benchmark::DoNotOptimize(simulate(tf, pair().ruu.r, 0.01));
}
BENCHMARK(BM_LsimReference256);

void BM_EstimateMmfmAuto(benchmark::State& state) {
  MmfmOptions opt;
  opt.order = {2, 0};
  for (auto _ : state) benchmark::DoNotOptimize(estimate_mmfm(pair().ruu, pair().ryu, opt));
}
BENCHMARK(BM_EstimateMmfmAuto)->Unit(benchmark::kMillisecond);

void BM_SrivcFixedDelay10Min(benchmark::State& state) {
  const auto rec = experiments::stornoway_record(1, 10.0);
  SrivcOptions so;
  so.order = {2, 0};
  so.delay_s = 0.06;
  for (auto _ : state) benchmark::DoNotOptimize(estimate_srivc(rec.u, rec.y, rec.dt_s, so));
}
BENCHMARK(BM_SrivcFixedDelay10Min)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rig::ident

BENCHMARK_MAIN();
