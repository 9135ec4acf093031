// CVODE accuracy figures for plantsim: against an analytic second-order step response, and
// the stornoway plant at its default tolerances against a tight-tolerance run.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/genset_plant.hpp"
#include "plantsim/solver/cvode_solver.hpp"

namespace plantsim {
namespace {

// x'' + 2 zeta wn x' + wn^2 x = wn^2, the plant's 2 Hz / 0.1 mode as a unit step.
class Mode : public OdeSystem {
 public:
  static constexpr double kWn = 2.0 * std::numbers::pi * 2.0;
  static constexpr double kZeta = 0.1;
  int size() const override { return 2; }
  bool derivatives(double, const double* x, double* dx) override {
    dx[0] = x[1];
    dx[1] = kWn * kWn * (1.0 - x[0]) - 2.0 * kZeta * kWn * x[1];
    return true;
  }
  static double exact(double t) {
    const double wd = kWn * std::sqrt(1.0 - kZeta * kZeta);
    return 1.0 -
           std::exp(-kZeta * kWn * t) * (std::cos(wd * t) + kZeta * kWn / wd * std::sin(wd * t));
  }
};

// range(0): 0 = a stop at every 1 ms tick, 1 = look-ahead of 58 ms (the plant's dead time).
void BM_CvodeVsAnalytic(benchmark::State& state) {
  const double look_ahead_s = state.range(0) == 0 ? 0.0 : 0.0583;
  double max_err = 0.0;
  long steps = 0;
  for (auto _ : state) {
    Mode ode;
    SolverOptions o;  // the plant's defaults (solver.rtol, solver.atol)
    o.rtol = 1e-8;
    o.atol = 2e-8;
    CvodeSolver solver(ode, 0.0, Eigen::Vector2d::Zero(), o);
    for (int k = 1; k <= 10000; ++k) {
      solver.advance_to(k * 1e-3, k * 1e-3 + look_ahead_s);
      max_err = std::max(max_err, std::abs(solver.state()[0] - Mode::exact(k * 1e-3)));
    }
    steps = solver.stats().steps;
  }
  state.counters["max_abs_error_unit_step"] = max_err;
  state.counters["cvode_steps_per_10s"] = static_cast<double>(steps);
}
BENCHMARK(BM_CvodeVsAnalytic)->ArgName("look_ahead")->Arg(0)->Arg(1)->Iterations(1);

// The quiet plant for 20 s under a +-1 % square wave (2 s period; range(0) = 0) or white
// Gaussian noise of 0.5 % rms changing every tick (range(0) = 1, seed 11), default tolerances
// vs rtol 1e-10 / atol 1e-12: worst difference of the true electrical power, kW.
void BM_PlantVsTightTolerance(benchmark::State& state) {
  Params p = preset("stornoway");
  for (P id : {P::kMeasNoise, P::kMeasPickup, P::kMeasDrift, P::kMeasQuant, P::kEngRipple}) {
    p.set(id, 0.0, "bench");
  }
  Params tight = p;
  tight.set(P::kSolverRtol, 1e-10, "bench");
  tight.set(P::kSolverAtol, 1e-12, "bench");
  double max_err_kw = 0.0, max_swing_kw = 0.0;
  for (auto _ : state) {
    GensetPlant a(p, {}, 1, std::chrono::milliseconds(1));
    GensetPlant b(tight, {}, 1, std::chrono::milliseconds(1));
    std::mt19937_64 rng(11);
    std::normal_distribution<double> normal(0.0, 0.5);
    for (int k = 0; k < 20000; ++k) {
      const double square = (k / 1000) % 2 == 0 ? 1.0 : -1.0;
      const double bias = state.range(0) == 0 ? square : normal(rng);
      a.set_bias_pct(bias);
      b.set_bias_pct(bias);
      a.step();
      b.step();
      max_err_kw =
          std::max(max_err_kw, std::abs(a.electrical_power_kw() - b.electrical_power_kw()));
      max_swing_kw = std::max(max_swing_kw, std::abs(b.electrical_power_kw() - 3500.0));
    }
  }
  state.counters["max_power_error_kw"] = max_err_kw;
  state.counters["max_power_swing_kw"] = max_swing_kw;
}
BENCHMARK(BM_PlantVsTightTolerance)
    ->ArgName("square0_gauss1")
    ->Arg(0)
    ->Arg(1)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace plantsim
