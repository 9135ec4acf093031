// The whole nonlinear plant: step response against the linear model, timed changes applied
// at their exact plant time, injector faults, seeded determinism and islanded operation.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <iostream>
#include <numbers>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/genset_plant.hpp"
#include "plantsim/plant/linearise.hpp"
#include "rig/model/transfer_function.hpp"

namespace plantsim {
namespace {

using std::chrono::milliseconds;

Params quiet(const std::string& name = "stornoway") {
  Params p = preset(name);
  for (P id : {P::kMeasNoise, P::kMeasPickup, P::kMeasDrift, P::kMeasQuant, P::kEngRipple}) {
    p.set(id, 0.0, "test");
  }
  return p;
}

TEST(PlantSim, BiasStepMatchesLinearModel) {
  const Params p = quiet();
  const LinearModel lm = linearise(p, "stornoway");
  GensetPlant plant(p, {}, 1, milliseconds(1));
  const int n = 25000;
  const double dt = 1e-3, t_step = 1.0, step_pct = 0.5;
  const double y0 = plant.measure().power_w / 1e3;
  Eigen::VectorXd y(n), u(n);
  for (int k = 0; k < n; ++k) {  // sample k is at t = k dt; the bias acts from t_step on
    y[k] = plant.measure().power_w / 1e3 - y0;
    u[k] = k * dt >= t_step ? step_pct : 0.0;
    plant.set_bias_pct(u[k]);
    plant.step();
  }
  // rig_model's simulation takes u as linear between samples: the step rises over the
  // sample before t_step instead of at t_step, half a millisecond early on average.
  const Eigen::VectorXd yhat = rig::model::simulate(lm.tf, u, dt);
  const double fit = rig::model::fit_percent(y, yhat);
  std::cout << "nonlinear vs linear TF step fit " << fit << " %, final " << y[n - 1] << " kW\n";
  EXPECT_GE(fit, 95.0);
  EXPECT_NEAR(y[n - 1], step_pct * 46.0, 0.5);  // settles at 1 % -> 46 kW per %
}

TEST(PlantSim, ChangeMidTickActsFromItsExactTime) {
  const Params p = quiet();
  GensetPlant base(p, {}, 1, milliseconds(1));
  GensetPlant cut(p, {parse_change("injector_3=0@t=1.0005")}, 1, milliseconds(1));
  for (int k = 0; k < 1000; ++k) {
    base.step();
    cut.step();
  }
  ASSERT_EQ(base.state(), cut.state());  // identical up to t = 1.000
  base.step();
  cut.step();
  // From 1.0005 to 1.001 the torque target drops by f/12 (f: delayed rack, constant here):
  // dm = -(f/12)(1 - exp(-0.0005/Tc)).
  const double f = base.rack_pu();
  const double tc = p[P::kEngCombustionLag];
  const double expected = -(f / 12.0) * (1.0 - std::exp(-0.0005 / tc));
  const int m = GensetModel::kEng + Engine::kTorque;
  EXPECT_NEAR(cut.state()[m] - base.state()[m], expected, 0.01 * std::abs(expected));
}

TEST(PlantSim, ChangeOnTickBoundaryShowsInThatTicksMeasurement) {
  GensetPlant plant(quiet(), {parse_change("meas.gain=1.1@t=0.002")}, 1, milliseconds(1));
  plant.step();
  const double before = plant.measure().power_w;
  plant.step();
  EXPECT_DOUBLE_EQ(plant.measure().time_s, 0.002);
  EXPECT_NEAR(plant.measure().power_w / before, 1.1, 1e-9);
}

double amplitude(const std::vector<double>& y, double dt, double freq_hz) {
  std::complex<double> s{0.0, 0.0};
  for (std::size_t k = 0; k < y.size(); ++k) {
    s += y[k] * std::polar(1.0, -2.0 * std::numbers::pi * freq_hz * k * dt);
  }
  return 2.0 * std::abs(s) / static_cast<double>(y.size());
}

TEST(PlantSim, DeadInjectorCutsPowerAndAddsCycleRipple) {
  Params p = quiet();
  p.set(P::kEngRipple, 1.0, "test");
  GensetPlant plant(p, {parse_change("injectors_out=1@t=2")}, 1, milliseconds(1));
  std::vector<double> before, after;
  double min_kw = 1e9;
  for (int k = 1; k <= 30000; ++k) {
    plant.step();
    const double y = plant.measure().power_w / 1e3;
    if (k >= 1000 && k < 2000) before.push_back(y);  // the change lands at t = 2.000
    if (k > 2000 && k <= 6000) min_kw = std::min(min_kw, y);
    if (k > 28000) after.push_back(y);
  }
  std::cout << "5 Hz ripple before " << amplitude(before, 1e-3, 5.0) << " kW, after "
            << amplitude(after, 1e-3, 5.0) << " kW; dip to " << min_kw << " kW\n";
  EXPECT_LT(amplitude(before, 1e-3, 5.0), 0.01);
  EXPECT_GT(amplitude(after, 1e-3, 5.0), 10.0);
  EXPECT_LT(min_kw, 3500.0 - 100.0);  // one of 12 cylinders lost: ~290 kW of torque
  double mean_after = 0.0;
  for (double y : after) mean_after += y / after.size();
  EXPECT_NEAR(mean_after, 3500.0, 5.0);  // the power loop restores the setpoint
}

std::vector<double> noisy_run(std::uint64_t seed) {
  GensetPlant plant(preset("stornoway"), {}, seed, milliseconds(1));
  std::vector<double> y;
  for (int k = 0; k < 2000; ++k) {
    plant.set_bias_pct((k / 50) % 2 == 0 ? 0.5 : -0.5);
    plant.step();
    y.push_back(plant.measure().power_w);
  }
  return y;
}

TEST(PlantSim, SameSeedGivesBitIdenticalOutput) {
  EXPECT_EQ(noisy_run(5), noisy_run(5));
  EXPECT_NE(noisy_run(5), noisy_run(6));
}

TEST(PlantSim, IslandedSetHoldsFrequencyWithDroop) {
  GensetPlant plant(quiet("stornoway_island"), {parse_change("load.step_pu=0.02@t=1")}, 1,
                    milliseconds(1));
  for (int k = 0; k < 20000; ++k) plant.step();
  const Measurement m = plant.measure();
  EXPECT_FALSE(m.fault) << plant.last_error();
  EXPECT_FALSE(m.breaker_closed);
  // More load: the speed falls until the governor and the load's own D_L balance it.
  EXPECT_LT(m.freq_hz, 50.0);
  EXPECT_GT(m.freq_hz, 49.0);
  EXPECT_NEAR(plant.electrical_power_kw(), 3500.0 + 0.02 * 4600.0, 30.0);
}

TEST(PlantSim, MakePlantValidatesOptions) {
  PlantOptions o;
  o.tick = std::chrono::nanoseconds(0);
  EXPECT_THROW(make_plant(o), ConfigError);
  o = PlantOptions{};
  o.preset = "nowhere";
  EXPECT_THROW(make_plant(o), ConfigError);
  o = PlantOptions{};
  o.faults = {"op.power_kw=4500@t=1"};
  auto plant = make_plant(o);
  EXPECT_NEAR(plant->measure().power_w, 3.5e6, 50e3);
  EXPECT_EQ(plant->rated_power_w(), 4.6e6);
}

TEST(PlantSim, DeadTimeBeyondTheHistoryIsAConfigError) {
  try {
    // 30/60 + 60/(2 * 60) = 1.0 s is still held; 1 cylinder at 60 rpm needs 1.5 s.
    GensetPlant plant(preset("stornoway"),
                      {parse_change("engine.cylinders=2@t=4"), parse_change("engine.rpm=60@t=5"),
                       parse_change("engine.cylinders=1@t=6")},
                      1, milliseconds(1));
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("engine.cylinders=1@t=6"), std::string::npos) << e.what();
  }
}

TEST(PlantSim, ImpossibleOperatingPointIsAConfigError) {
  Params p = preset("stornoway");
  p.set(P::kPowerKw, 9000.0, "test");
  EXPECT_THROW(GensetPlant(p, {}, 1, milliseconds(1)), ConfigError);
}

}  // namespace
}  // namespace plantsim

namespace plantsim {
namespace {

// The exact bias path (superposition) against the bias entering e inside the ODE: a tiny
// deadband forces the latter, which must give the same response.
TEST(PlantSim, ExactBiasPathEqualsBiasInsideTheOde) {
  Params exact = quiet();  // tight tolerances so that only the formulations are compared
  exact.set(P::kSolverRtol, 1e-9, "test");
  exact.set(P::kSolverAtol, 1e-11, "test");
  Params inside = exact;
  inside.set(P::kGovDeadband, 1e-12, "test");
  GensetPlant a(exact, {}, 1, milliseconds(1));
  GensetPlant b(inside, {}, 1, milliseconds(1));
  ASSERT_TRUE(a.split_bias_path());
  ASSERT_FALSE(b.split_bias_path());
  double worst_kw = 0.0;
  for (int k = 0; k < 6000; ++k) {
    const double bias = (k / 700) % 2 == 0 ? 1.0 : -0.5;
    a.set_bias_pct(bias);
    b.set_bias_pct(bias);
    a.step();
    b.step();
    worst_kw = std::max(worst_kw, std::abs(a.electrical_power_kw() - b.electrical_power_kw()));
  }
  std::cout << "split vs in-ODE bias path: worst difference " << worst_kw << " kW\n";
  EXPECT_LT(worst_kw, 0.01);  // swings are ~70 kW
}

TEST(PlantSim, ActuatorLimitHoldsWithoutWindUpOnTheExactPath) {
  GensetPlant plant(quiet(), {}, 1, milliseconds(1));
  ASSERT_TRUE(plant.split_bias_path());
  const double tmax = plant.params()[P::kGovTmax];
  plant.set_bias_pct(60.0);
  double highest = 0.0;
  for (int k = 0; k < 8000; ++k) {
    plant.step();
    highest = std::max(highest, plant.actuator_pu());
  }
  EXPECT_LE(highest, tmax + 1e-12);
  EXPECT_NEAR(plant.actuator_pu(), tmax, 1e-9);  // pinned at the limit for seconds
  plant.set_bias_pct(-60.0);
  for (int k = 0; k < 300; ++k) plant.step();
  // Without wind-up the actuator leaves the stop at once.
  EXPECT_LT(plant.actuator_pu(), tmax - 0.05);
}

TEST(PlantSim, SwitchingToTheInOdePathMidRunIsSeamless) {
  GensetPlant a(quiet(), {}, 1, milliseconds(1));
  GensetPlant b(quiet(), {parse_change("gov.deadband_pu=1e-12@t=1.5")}, 1, milliseconds(1));
  double worst_kw = 0.0;
  for (int k = 0; k < 4000; ++k) {
    a.set_bias_pct(k >= 1000 ? 1.0 : 0.0);
    b.set_bias_pct(k >= 1000 ? 1.0 : 0.0);
    a.step();
    b.step();
    worst_kw = std::max(worst_kw, std::abs(a.electrical_power_kw() - b.electrical_power_kw()));
  }
  EXPECT_FALSE(b.split_bias_path());
  EXPECT_LT(worst_kw, 0.5);
}

TEST(PlantSim, FluxDecayAndAvrStartInEquilibrium) {
  Params p = quiet();
  p.set(P::kAltFluxDecay, 1.0, "test");
  p.set(P::kAltAvr, 1.0, "test");
  GensetPlant plant(p, {}, 1, milliseconds(1));
  const double v0 = plant.measure().voltage_v;
  for (int k = 0; k < 3000; ++k) plant.step();
  EXPECT_NEAR(plant.electrical_power_kw(), 3500.0, 1e-3);
  EXPECT_NEAR(plant.measure().voltage_v, v0, 1e-3);
  plant.set_bias_pct(1.0);
  for (int k = 0; k < 20000; ++k) plant.step();
  EXPECT_FALSE(plant.measure().fault) << plant.last_error();
  EXPECT_NEAR(plant.electrical_power_kw(), 3546.0, 2.0);
  // The AVR holds the terminal voltage close to its reference under the new load.
  EXPECT_NEAR(plant.measure().voltage_v / v0, 1.0, 0.01);
}

}  // namespace
}  // namespace plantsim

namespace plantsim {
namespace {

// A large load step hits the MAP limiter (limit 0.2 + 0.9 boost below the new fuel demand
// until the boost has built up): a fouled turbocharger (slower boost lag) slows the rise.
double power_after(double boost_lag_s, double seconds) {
  Params p = quiet();
  p.set(P::kEngMapMin, 0.2, "test");
  GensetPlant plant(p, {parse_change("engine.boost_lag_s=" + std::to_string(boost_lag_s) + "@t=0")},
                    1, milliseconds(1));
  plant.set_bias_pct(20.0);
  for (int k = 0; k < static_cast<int>(seconds * 1000); ++k) plant.step();
  return plant.electrical_power_kw();
}

TEST(PlantSim, TurboFoulingSlowsTheMapLimitedLoadRise) {
  const double clean_kw = power_after(2.0, 1.5);
  const double fouled_kw = power_after(6.0, 1.5);
  std::cout << "after 1.5 s: clean " << clean_kw << " kW, fouled " << fouled_kw << " kW\n";
  EXPECT_LT(fouled_kw, clean_kw - 50.0);
  EXPECT_NEAR(power_after(6.0, 40.0), 3500.0 + 0.2 * 4600.0, 10.0);  // boost catches up
}

}  // namespace
}  // namespace plantsim
