// Layers 1 and 2 together against a resonant plant: the amplitude plan from a (possibly
// wrong) prior gain, then the supervisor's back-off, must keep every sample inside the band.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "rig/session/amplitude_plan.hpp"
#include "rig/session/supervisor.hpp"
#include "sim.hpp"

namespace rig::session {
namespace {

constexpr double kExcitationBandwidthHz = 4.0;  // about twice the 2 Hz resonance

struct RunResult {
  int outside = 0;  // samples with |P - P0| > band while excitation was active
  double max_dev_kw = 0.0;
  double min_scale = 1.0;
  bool tripped = false;
  int open_loop_outside = 0;  // the same excitation without layer 2
};

// prior_factor: the prior's rms gain divided by the true one (0.3 = a prior three times too
// optimistic, so the plan is three times too large).
RunResult run(double prior_factor, unsigned seed, double duration_s) {
  const testing::PlantParams p;
  const double band_kw = 0.03 * p.p0_kw;
  const double true_gain =
      prior_gain_rms([&p](double f) { return p.magnitude(f); }, kExcitationBandwidthHz);
  AmplitudePlanOptions ao;
  ao.band_kw = band_kw;
  const AmplitudePlan plan = plan_excitation(prior_factor * true_gain, p.noise_rms_kw, ao);
  EXPECT_TRUE(plan.feasible) << plan.reason;
  const auto n = static_cast<Eigen::Index>(duration_s / p.dt_s);
  const Eigen::VectorXd e =
      plan.excitation_rms_pct * testing::filtered_noise(n, p.dt_s, kExcitationBandwidthHz, seed);

  SupervisorConfig c;
  c.p0_kw = p.p0_kw;
  c.dt_s = p.dt_s;
  c.noise_rms_kw = p.noise_rms_kw;
  Supervisor sup(c);
  sup.start();
  testing::SimPlant plant(p, seed + 1);
  testing::SimPlant open_loop(p, seed + 1);
  RunResult r;
  for (Eigen::Index k = 0; k < n; ++k) {
    const SupervisorOutput out = sup.tick(plant.sample(), e(k));
    r.min_scale = std::min(r.min_scale, k > 1000 ? out.scale : 1.0);  // after the soft start
    const double dev = plant.step(out.bias_pct).power_kw - p.p0_kw;
    r.max_dev_kw = std::max(r.max_dev_kw, std::abs(dev));
    r.outside += std::abs(dev) > band_kw;
    // The open-loop twin sees the same soft start so only the back-off differs.
    const double soft =
        std::min(1.0, static_cast<double>(k + 1) * c.backoff.recover_rate_per_s * p.dt_s);
    r.open_loop_outside += std::abs(open_loop.step(soft * e(k)).power_kw - p.p0_kw) > band_kw;
  }
  r.tripped = sup.tripped();
  return r;
}

TEST(SupervisorBackoff, KeepsResonantPlantInsideBandWithThreeTimesTooLargeExcitation) {
  const unsigned seed = 424242;
  const RunResult r = run(0.3, seed, 60.0);
  std::printf("seed %u: max |P-P0| %.1f kW of 105.0, min scale %.2f, open loop outside %d\n", seed,
              r.max_dev_kw, r.min_scale, r.open_loop_outside);
  EXPECT_EQ(r.outside, 0);
  EXPECT_FALSE(r.tripped);
  EXPECT_LT(r.min_scale, 0.5);        // the back-off did the work
  EXPECT_GT(r.open_loop_outside, 0);  // without it this excitation leaves the band
}

TEST(SupervisorBackoff, SeededSweepOfWrongPriorsNeverLeavesTheBand) {
  const unsigned master_seed = 20261121;
  std::mt19937 rng(master_seed);
  std::uniform_real_distribution<double> log_factor(std::log(0.3), std::log(3.0));
  std::uniform_int_distribution<unsigned> seeds(1, 1u << 30);
  int runs_outside = 0, runs_tripped = 0, open_loop_runs_outside = 0;
  double worst = 0.0;
  std::printf("master seed %u; per run: seed prior_factor max|P-P0|/band min_scale\n", master_seed);
  for (int i = 0; i < 200; ++i) {
    const double factor = std::exp(log_factor(rng));
    const unsigned seed = seeds(rng);
    const RunResult r = run(factor, seed, 40.0);
    std::printf("%u %.3f %.3f %.2f%s\n", seed, factor, r.max_dev_kw / 105.0, r.min_scale,
                r.outside > 0 ? " OUTSIDE" : "");
    runs_outside += r.outside > 0;
    runs_tripped += r.tripped;
    open_loop_runs_outside += r.open_loop_outside > 0;
    worst = std::max(worst, r.max_dev_kw / 105.0);
  }
  std::printf(
      "runs outside %d, tripped %d, worst %.3f of band; without back-off %d runs "
      "would have left the band\n",
      runs_outside, runs_tripped, worst, open_loop_runs_outside);
  EXPECT_EQ(runs_outside, 0);
  EXPECT_EQ(runs_tripped, 0);
  EXPECT_GT(open_loop_runs_outside, 0);
}

}  // namespace
}  // namespace rig::session
