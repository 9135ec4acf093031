// Layers 1 and 2 against the emulated Stornoway set (plantsim, CVODE), driven directly at a
// 10 ms session tick (10 plant ticks of 1 ms): the amplitude planned from the plant's own
// linearisation, right or three times too optimistic, never takes the power out of the band.
#include <gtest/gtest.h>

#include <cstdio>

#include "plantsim/plant/linearise.hpp"
#include "plantsim/plant/plant.hpp"
#include "rig/session/amplitude_plan.hpp"
#include "rig/session/supervisor.hpp"
#include "sim.hpp"

namespace rig::session {
namespace {

constexpr double kDt = 0.01;
constexpr int kPlantTicksPerTick = 10;

struct PlantRun {
  double worst_fraction = 0.0;  // max |P - P0| / band during excitation
  double min_scale = 1.0;
  bool tripped = false;
};

PlantRun run_stornoway(const plantsim::LinearModel& lin, double prior_factor, unsigned seed) {
  plantsim::PlantOptions po;
  po.seed = seed;
  auto plant = plantsim::make_plant(po);
  // Steady-state record (3 s): P0 and the noise, as the steady-state phase would give them.
  double sum = 0.0, sum2 = 0.0;
  const int n0 = 300;
  for (int k = 0; k < n0; ++k) {
    for (int i = 0; i < kPlantTicksPerTick; ++i) plant->step();
    const double p = plant->measure().power_w / 1e3;
    sum += p;
    sum2 += p * p;
  }
  const double p0 = sum / n0;
  const double noise = std::sqrt(std::max(sum2 / n0 - p0 * p0, 0.0));
  const double band = 0.03 * p0;
  AmplitudePlanOptions ao;
  ao.band_kw = band;
  const double prior_gain =
      prior_gain_rms([&](double f) { return prior_factor * std::abs(lin.response(f)); }, 4.0);
  const AmplitudePlan plan = plan_excitation(prior_gain, noise, ao);
  EXPECT_TRUE(plan.feasible) << plan.reason;
  const Eigen::Index n = 4000;  // 40 s
  const Eigen::VectorXd e = plan.excitation_rms_pct * testing::filtered_noise(n, kDt, 4.0, seed);
  SupervisorConfig c;
  c.p0_kw = p0;
  c.dt_s = kDt;
  c.noise_rms_kw = noise;
  c.backoff.resonance_hz = lin.fn_hz;
  Supervisor sup(c);
  sup.start();
  drivers::Sample s;
  s.status = drivers::kRunning | drivers::kBreakerClosed;
  PlantRun r;
  for (Eigen::Index k = 0; k < n; ++k) {
    s.power_kw = plant->measure().power_w / 1e3;
    ++s.counter;
    const SupervisorOutput out = sup.tick(s, e(k));
    plant->set_bias_pct(out.bias_pct);
    for (int i = 0; i < kPlantTicksPerTick; ++i) plant->step();
    r.worst_fraction =
        std::max(r.worst_fraction, std::abs(plant->measure().power_w / 1e3 - p0) / band);
    if (k > 1000) r.min_scale = std::min(r.min_scale, out.scale);  // after the soft start
  }
  r.tripped = sup.tripped();
  return r;
}

TEST(SupervisorBackoff, StornowayPlantStaysInBandWithRightAndOptimisticPriors) {
  plantsim::PlantOptions po;
  const plantsim::LinearModel lin = plantsim::linearise(po);
  for (double factor : {1.0, 0.5, 0.3}) {
    for (unsigned seed : {11u, 12u, 13u}) {
      const PlantRun r = run_stornoway(lin, factor, seed);
      std::printf("stornoway prior factor %.1f seed %u: max |P-P0| %.3f of band, min scale %.2f\n",
                  factor, seed, r.worst_fraction, r.min_scale);
      EXPECT_LT(r.worst_fraction, 1.0) << "factor " << factor << " seed " << seed;
      EXPECT_FALSE(r.tripped) << "factor " << factor << " seed " << seed;
      if (factor == 0.3) {
        EXPECT_LT(r.min_scale, 0.6) << "the back-off should have acted";
      }
    }
  }
}

}  // namespace
}  // namespace rig::session
