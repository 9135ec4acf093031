#include "rig/fra/stepped_sine.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "second_order.hpp"

namespace rig::fra {
namespace {

constexpr double kDt = 0.01;

TEST(SweepPlan, LogGridTimingAndAmplitudeRules) {
  const auto grid = log_grid_hz(0.2, 10.0, 20);
  ASSERT_EQ(grid.size(), 20u);
  EXPECT_DOUBLE_EQ(grid.front(), 0.2);
  EXPECT_DOUBLE_EQ(grid.back(), 10.0);
  EXPECT_NEAR(grid[1] / grid[0], std::pow(50.0, 1.0 / 19.0), 1e-12);

  SweepPlanOptions o;
  o.f_start_hz = 2.0;
  o.f_stop_hz = 2.0;
  o.points = 1;
  o.amplitude.band_kw = 100.0;
  o.amplitude.noise_peak_kw = 10.0;
  o.amplitude.max_amplitude_pct = 5.0;
  const ResponseFn flat = [](double) { return std::complex<double>(20.0, 0.0); };
  const SweepPlan plan = make_sweep_plan(o, flat);
  ASSERT_EQ(plan.points.size(), 1u);
  const SweepPoint& p = plan.points[0];
  // settle = max(5 * 0.8 s * 2 Hz, 3) = 8 cycles; integrate = max(8, 4 s * 2 Hz) = 8 cycles.
  EXPECT_EQ(p.settle_cycles, 8);
  EXPECT_EQ(p.integrate_cycles, 8);
  EXPECT_EQ(p.settle_samples, 400);
  EXPECT_EQ(p.integrate_samples, 400);
  EXPECT_EQ(p.ramp_samples, 50);
  // A = (0.8 * 100 - 10) / (1.5 * 20) kW / (kW/%).
  EXPECT_NEAR(p.amplitude_pct, 70.0 / 30.0, 1e-12);
  EXPECT_NEAR(p.predicted_peak_kw, 70.0 / 1.5 + 10.0, 1e-9);

  o.amplitude.max_amplitude_pct = 1.0;
  EXPECT_DOUBLE_EQ(make_sweep_plan(o, flat).points[0].amplitude_pct, 1.0);
}

TEST(SweepPlan, NoiseRuleLengthensLowResponsePoints) {
  SweepPlanOptions o;
  o.f_start_hz = 2.0;
  o.f_stop_hz = 2.0;
  o.points = 1;
  o.amplitude.band_kw = 100.0;
  o.amplitude.max_amplitude_pct = 0.5;
  const ResponseFn flat = [](double) { return std::complex<double>(20.0, 0.0); };
  EXPECT_EQ(make_sweep_plan(o, flat).points[0].integrate_cycles, 8);  // rule off by default
  // |Y| = 0.5 % * 20 kW/% = 10 kW; 2 * 5^2 * 0.01 / (0.02 * 10)^2 = 12.5 s -> 25 cycles.
  o.noise_rms_kw = 5.0;
  o.target_rel_std = 0.02;
  EXPECT_EQ(make_sweep_plan(o, flat).points[0].integrate_cycles, 25);
  o.max_integrate_s = 6.0;  // the cap wins
  EXPECT_EQ(make_sweep_plan(o, flat).points[0].integrate_cycles, 12);
  o.noise_rms_kw = 0.5;  // 0.125 s: the minimum of 4 s wins
  EXPECT_EQ(make_sweep_plan(o, flat).points[0].integrate_cycles, 8);
  o.target_rel_std = -1.0;
  EXPECT_THROW(make_sweep_plan(o, flat), std::invalid_argument);
}

TEST(SweepPlan, AmplitudeUsesLargestPriorGainNearby) {
  AmplitudeLimits l;
  l.band_kw = 100.0;
  // A prior with a sharp peak at 2.2 Hz: planning at 2 Hz must see it (within +-15 %).
  const ResponseFn peaky = [](double f) {
    return std::complex<double>(std::abs(f - 2.2) < 0.05 ? 200.0 : 10.0, 0.0);
  };
  EXPECT_NEAR(sine_amplitude_pct(peaky, 2.0, l), 80.0 / (1.5 * 200.0), 1e-12);
  EXPECT_NEAR(sine_amplitude_pct(peaky, 1.0, l), std::min(1.0, 80.0 / (1.5 * 10.0)), 1e-12);
}

TEST(SweepPlan, RejectsBadOptions) {
  const ResponseFn flat = [](double) { return std::complex<double>(1.0, 0.0); };
  SweepPlanOptions o;
  o.amplitude.band_kw = 100.0;
  o.f_stop_hz = 45.0;  // above 0.4 / dt
  EXPECT_THROW(make_sweep_plan(o, flat), std::invalid_argument);
  o.f_stop_hz = 10.0;
  EXPECT_NO_THROW(make_sweep_plan(o, flat));
  EXPECT_THROW(make_sweep_plan(o, ResponseFn{}), std::invalid_argument);
  o.amplitude.noise_peak_kw = 80.0;  // no headroom left in 0.8 * band
  EXPECT_THROW(make_sweep_plan(o, flat), std::invalid_argument);
}

// The whole streaming loop against a ZOH plant whose exact discrete response is known.
TEST(SteppedSine, StreamingSweepRecoversDiscretePlantResponse) {
  const testing::SecondOrderDelay g;
  testing::DiscretePlant plant(g, kDt);
  SweepPlanOptions o;
  o.dt_s = kDt;
  o.amplitude.band_kw = 105.0;  // 3 % of 3.5 MW
  o.amplitude.noise_peak_kw = 0.1;
  const SweepPlan plan = make_sweep_plan(o, as_response_fn(g));
  SteppedSineAnalyser sweep(plan);
  const unsigned seed = 7;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.02);  // kW: good SNR even at 10 Hz
  double max_dev_kw = 0.0;
  int reported = 0;
  while (!sweep.done()) {
    const double e = sweep.excitation_pct();
    const double y = plant.step(e);
    max_dev_kw = std::max(max_dev_kw, std::abs(y));
    if (sweep.push(e, 3500.0 + y + noise(rng))) ++reported;
  }
  SCOPED_TRACE("seed " + std::to_string(seed));
  EXPECT_EQ(reported, 20);
  // The amplitude rule keeps the (noise-free) response inside the planned 80 % of the band.
  EXPECT_LT(max_dev_kw, 0.8 * o.amplitude.band_kw);
  for (const SteppedSineResult& r : sweep.results()) {
    SCOPED_TRACE("f = " + std::to_string(r.point.freq_hz));
    const std::complex<double> h = plant.response(r.point.freq_hz);
    EXPECT_TRUE(r.good);
    EXPECT_NEAR(model::to_db(r.mag), model::to_db(std::abs(h)), 0.05);
    EXPECT_NEAR(model::wrap_deg(r.phase_deg - std::arg(h) * 180.0 / std::numbers::pi), 0.0, 0.3);
    EXPECT_LT(r.distortion, 1e-3);
    const model::FrfPoint p = r.frf_point();
    EXPECT_LE(p.mag_lo, p.mag);
    EXPECT_GE(p.mag_hi, p.mag);
  }
  EXPECT_EQ(sweep.excitation_pct(), 0.0);
  EXPECT_EQ(sweep.frf().size(), 20u);
}

TEST(SteppedSine, BackOffDuringIntegrationMarksPointInvalid) {
  const testing::SecondOrderDelay g;
  testing::DiscretePlant plant(g, kDt);
  SweepPlanOptions o;
  o.f_start_hz = o.f_stop_hz = 1.0;
  o.points = 1;
  o.amplitude.band_kw = 105.0;
  SteppedSineAnalyser sweep(make_sweep_plan(o, as_response_fn(g)));
  const SweepPoint p = sweep.plan().points[0];
  std::optional<SteppedSineResult> r;
  for (Eigen::Index n = 0; !sweep.done(); ++n) {
    // Halve the applied excitation in the middle of the integration window.
    const double scale = n > p.settle_samples + p.integrate_samples / 2 ? 0.5 : 1.0;
    const double u = scale * sweep.excitation_pct();
    EXPECT_EQ(sweep.phase(), n < p.settle_samples ? SteppedSineAnalyser::Phase::kSettling
                                                  : SteppedSineAnalyser::Phase::kIntegrating);
    r = sweep.push(u, plant.step(u));
  }
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->good);
  EXPECT_FALSE(r->frf_point().valid);
}

}  // namespace
}  // namespace rig::fra
