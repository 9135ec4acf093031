// plantsim speed and accuracy (DESIGN.md section 7).
//
// Speed: the full nonlinear stornoway preset (noise, pick-up, drift, quantisation, firing
// ripple) stepped in-process at 1 ms ticks under four bias excitations, with two references
// timed in the same iteration: the same plant without ripple/noise ("quiet") and the linear
// model (its TF + dead time as a discrete state space). Counters are simulated seconds per
// wall second (and per CPU second, which is what a loaded machine still gives one process).
// Measured on 2 shared cores, median of 3 runs, simulated s per CPU s (cost over the linear
// model), before -> after the engine lags went into closed form (EnginePath) with the retuned
// tolerances: step 2,178 (10) -> 2,072 (14); PRBS 454 (58) -> 982 (29); Gaussian per tick
// 185 (151) -> 992 (29); Gaussian held 10 ms 257 (102) -> 898 (32). Ranges in
// plantsim/presets/README.md.
//
// Accuracy: CVODE against the analytic step response of a second-order block, and the plant
// at its default tolerances against a tight-tolerance run of the same excitation.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <numbers>
#include <random>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/genset_plant.hpp"
#include "plantsim/plant/linearise.hpp"
#include "rig/model/transfer_function.hpp"

namespace plantsim {
namespace {

using std::chrono::milliseconds;
constexpr int kTicks = 20000;  // 20 s per run
constexpr double kDt = 1e-3;

enum Excitation { kStep = 0, kPrbs = 1, kGaussian = 2, kGaussian10ms = 3 };
constexpr int kRigSampleTicks = 10;  // the rig's 100 Hz sample period in 1 ms plant ticks

// Bias in % of rated power: 0.5 % steps every 5 s; a 9-bit PRBS (x^9 + x^5 + 1) of +-1 %
// clocked every 50 ms; white Gaussian noise of 0.5 % rms changing every tick (seed 11), or
// held for 10 ms as a rig sampling at 100 Hz sends it.
std::vector<double> excitation(Excitation kind) {
  std::vector<double> u(kTicks);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, 0.5);
  unsigned lfsr = 0x1ff;
  for (int k = 0; k < kTicks; ++k) {
    if (kind == kStep) u[k] = (k / 5000) % 2 == 1 ? 0.5 : 0.0;
    if (kind == kGaussian) u[k] = normal(rng);
    if (kind == kGaussian10ms) u[k] = k % kRigSampleTicks == 0 ? normal(rng) : u[k - 1];
    if (kind == kPrbs) {
      if (k % 50 == 0) lfsr = ((lfsr << 1) | (((lfsr >> 8) ^ (lfsr >> 4)) & 1u)) & 0x1ffu;
      u[k] = (lfsr & 1u) != 0 ? 1.0 : -1.0;
    }
  }
  return u;
}

double cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Timing {
  double wall_s = 0.0, cpu_s = 0.0;
};

template <typename F>
Timing timed(F&& f) {
  const double c0 = cpu_s();
  const auto w0 = std::chrono::steady_clock::now();
  f();
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count(),
          cpu_s() - c0};
}

double run_plant(const Params& p, const std::vector<double>& u) {
  GensetPlant plant(p, {}, 1, milliseconds(1));
  double sum = 0.0;
  for (double b : u) {
    plant.set_bias_pct(b);
    plant.step();
    sum += plant.measure().power_w;
  }
  return sum;
}

// Linear reference: rig_model's exact simulation of the plant's linearised TF (the one
// transfer-function simulation of the project).
double run_linear(const LinearModel& lm, const std::vector<double>& u) {
  const Eigen::Map<const Eigen::VectorXd> in(u.data(), static_cast<Eigen::Index>(u.size()));
  return rig::model::simulate(lm.tf, in, kDt).sum();
}

Params quiet(Params p) {
  for (P id : {P::kMeasNoise, P::kMeasPickup, P::kMeasDrift, P::kMeasQuant, P::kEngRipple}) {
    p.set(id, 0.0, "bench");
  }
  return p;
}

void BM_PlantSpeed(benchmark::State& state) {
  const auto u = excitation(static_cast<Excitation>(state.range(0)));
  const Params full = preset("stornoway");
  const Params calm = quiet(full);
  const LinearModel lm = linearise(full, "stornoway");
  Timing nl, ref, lin;
  for (auto _ : state) {
    const Timing a = timed([&] { benchmark::DoNotOptimize(run_plant(full, u)); });
    const Timing b = timed([&] { benchmark::DoNotOptimize(run_plant(calm, u)); });
    const Timing c = timed([&] { benchmark::DoNotOptimize(run_linear(lm, u)); });
    nl.wall_s += a.wall_s, nl.cpu_s += a.cpu_s;
    ref.wall_s += b.wall_s, ref.cpu_s += b.cpu_s;
    lin.wall_s += c.wall_s, lin.cpu_s += c.cpu_s;
  }
  const double sim_s = static_cast<double>(state.iterations()) * kTicks * kDt;
  state.counters["nonlinear_sim_s_per_wall_s"] = sim_s / nl.wall_s;
  state.counters["nonlinear_sim_s_per_cpu_s"] = sim_s / nl.cpu_s;
  state.counters["quiet_sim_s_per_wall_s"] = sim_s / ref.wall_s;
  state.counters["linear_sim_s_per_wall_s"] = sim_s / lin.wall_s;
  state.counters["nonlinear_over_quiet_cost"] = nl.cpu_s / ref.cpu_s;
  state.counters["nonlinear_over_linear_cost"] = nl.cpu_s / lin.cpu_s;
}
BENCHMARK(BM_PlantSpeed)
    ->ArgName("excitation_step0_prbs1_gauss2_gauss10ms3")
    ->Arg(kStep)
    ->Arg(kPrbs)
    ->Arg(kGaussian)
    ->Arg(kGaussian10ms)
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace plantsim
BENCHMARK_MAIN();
