// The stepped sine (rig/fra) through the supervisor: with the amplitude planned from a prior
// that is right or three times too optimistic about the gain, the sweep must stay inside the
// band without a trip and still deliver valid points.
#include <gtest/gtest.h>

#include <cstdio>

#include "rig/fra/stepped_sine.hpp"
#include "rig/session/supervisor.hpp"
#include "sim.hpp"

namespace rig::session {
namespace {

struct SweepRun {
  double max_dev_kw = 0.0;
  double min_scale = 1.0;
  bool tripped = false;
  std::vector<fra::SteppedSineResult> results;
};

SweepRun supervised_sweep(double prior_factor, unsigned seed) {
  const testing::PlantParams p;
  fra::SweepPlanOptions o;
  o.dt_s = p.dt_s;
  o.amplitude.band_kw = 0.03 * p.p0_kw;
  o.amplitude.noise_peak_kw = 4.0 * p.noise_rms_kw;
  o.amplitude.max_amplitude_pct = 2.0;
  const fra::ResponseFn prior = [&](double f) {
    return std::complex<double>(prior_factor * p.magnitude(f), 0.0);
  };
  fra::SteppedSineAnalyser sweep(fra::make_sweep_plan(o, prior));
  SupervisorConfig c;
  c.p0_kw = p.p0_kw;
  c.dt_s = p.dt_s;
  c.noise_rms_kw = p.noise_rms_kw;
  c.backoff.peak_to_rms = 2.0;  // a sine: sqrt(2) and margin
  Supervisor sup(c);
  sup.start();
  testing::SimPlant plant(p, seed);
  SweepRun r;
  // The sweep starts once the soft start has reached full scale.
  const long soft_ticks = std::lround(1.0 / (c.backoff.recover_rate_per_s * c.dt_s));
  for (long k = 0; !sweep.done(); ++k) {
    const bool sweeping = k >= soft_ticks;
    const SupervisorOutput out = sup.tick(plant.sample(), sweeping ? sweep.excitation_pct() : 0.0);
    const double power_kw = plant.step(out.bias_pct).power_kw;
    r.max_dev_kw = std::max(r.max_dev_kw, std::abs(power_kw - p.p0_kw));
    if (sweeping) {
      r.min_scale = std::min(r.min_scale, out.scale);
      sweep.push(out.excitation_pct, power_kw);
    }
  }
  r.tripped = sup.tripped();
  r.results = sweep.results();
  return r;
}

TEST(SupervisedSweep, StaysInBandWithRightAndOptimisticPriors) {
  const testing::PlantParams p;
  const unsigned seed = 5;
  for (double factor : {1.0, 0.3}) {
    const SweepRun r = supervised_sweep(factor, seed);
    int good = 0;
    for (const auto& res : r.results) good += res.good;
    std::printf(
        "prior factor %.1f, seed %u: max |P-P0| %.1f kW of 105, min scale %.2f, %d/%zu "
        "points valid\n",
        factor, seed, r.max_dev_kw, r.min_scale, good, r.results.size());
    SCOPED_TRACE(factor);
    EXPECT_LT(r.max_dev_kw, 0.03 * p.p0_kw);
    EXPECT_FALSE(r.tripped);
    EXPECT_EQ(good, 20);
    for (const auto& res : r.results) {
      if (res.point.freq_hz < 0.5 || res.point.freq_hz > 5.0) continue;
      // Magnitude only: the ZOH plant adds half a sample of lag that the analytic |G| lacks.
      EXPECT_NEAR(model::to_db(res.mag), model::to_db(p.magnitude(res.point.freq_hz)), 0.5)
          << res.point.freq_hz << " Hz";
    }
  }
}

}  // namespace
}  // namespace rig::session
