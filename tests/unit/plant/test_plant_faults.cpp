// Timed changes as condition-monitoring faults: ramps, the transducer offset, load setpoint
// changes on the grid-connected and the islanded set, fractional injector faults.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <iostream>
#include <numbers>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/genset_plant.hpp"

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

std::vector<TimedChange> changes(std::initializer_list<const char*> texts) {
  std::vector<TimedChange> out;
  for (const char* t : texts) out.push_back(parse_change(t));
  return out;
}

void run_to(GensetPlant& plant, double t_s) {
  while (plant.measure().time_s < t_s - 1e-9) plant.step();
  ASSERT_FALSE(plant.measure().fault) << plant.last_error();
}

// Amplitude of the line at freq_hz over whole cycles of it (1 ms samples).
double line_kw(const std::vector<double>& y, double freq_hz) {
  std::complex<double> s{0.0, 0.0};
  for (std::size_t k = 0; k < y.size(); ++k) {
    s += y[k] * std::polar(1.0, -2.0 * std::numbers::pi * freq_hz * 1e-3 * k);
  }
  return 2.0 * std::abs(s) / static_cast<double>(y.size());
}

std::vector<double> measured_kw(GensetPlant& plant, double seconds) {
  std::vector<double> y;
  for (int k = 0; k < static_cast<int>(std::lround(seconds * 1000)); ++k) {
    plant.step();
    y.push_back(plant.measure().power_w / 1e3);
  }
  return y;
}

TEST(PlantFaults, RampPassesItsMidpointLinearly) {
  // 0 -> 100 kW from t = 1 to t = 11: 25 kW at 3.5 s, 50 kW at 6 s, then held at 100 kW.
  Params p = preset("stornoway");
  p.set(P::kMeasQuant, 0.0, "test");  // noise, drift and pick-up stay: same seed, same draws
  GensetPlant base(p, {}, 7, milliseconds(1));
  GensetPlant ramp(p, changes({"meas.offset_kw=100@t=1,ramp=10"}), 7, milliseconds(1));
  for (double t : {1.0, 3.5, 6.0, 11.0, 13.0}) {
    run_to(base, t);
    run_to(ramp, t);
    const double expected = std::clamp(10.0 * (t - 1.0), 0.0, 100.0);
    EXPECT_NEAR(ramp.params()[P::kMeasOffset], expected, 1e-9) << t;
    EXPECT_NEAR((ramp.measure().power_w - base.measure().power_w) / 1e3, expected, 1e-6) << t;
  }
}

TEST(PlantFaults, OffsetShowsInMeasuredPowerByExactlyItsSize) {
  Params p = preset("stornoway");
  p.set(P::kMeasQuant, 0.0, "test");
  GensetPlant base(p, {}, 3, milliseconds(1));
  GensetPlant off(p, changes({"meas.offset_kw=-37.5@t=0.5"}), 3, milliseconds(1));
  double worst_before = 0.0, worst_after = 0.0;
  for (int k = 1; k <= 2000; ++k) {
    base.step();
    off.step();
    const double d = (off.measure().power_w - base.measure().power_w) / 1e3;
    if (k < 500) worst_before = std::max(worst_before, std::abs(d));
    if (k >= 500) worst_after = std::max(worst_after, std::abs(d + 37.5));
  }
  EXPECT_EQ(worst_before, 0.0);
  EXPECT_LT(worst_after, 1e-9);
  EXPECT_EQ(off.electrical_power_kw(), base.electrical_power_kw());  // the plant is untouched
}

// A load setpoint step on the grid-connected set moves Pref = R P0 in DEGOV1's summing
// junction, like a bias of the same size: the power follows through the fuel dead time and
// the 2 Hz electromechanical mode, not as a jump of the operating point.
TEST(PlantFaults, LoadSetpointStepMovesGridPowerThroughTheGovernor) {
  GensetPlant plant(quiet(), changes({"op.power_kw=3800@t=1"}), 1, milliseconds(1));
  run_to(plant, 1.05);  // within the 58 ms fuel dead time: nothing has reached the shaft yet
  EXPECT_NEAR(plant.electrical_power_kw(), 3500.0, 0.01);
  run_to(plant, 1.1);
  EXPECT_LT(plant.electrical_power_kw(), 3650.0);  // not yet half-way 100 ms after the step
  double peak = 0.0;
  while (plant.measure().time_s < 3.0 - 1e-9) {
    plant.step();
    peak = std::max(peak, plant.electrical_power_kw());
  }
  EXPECT_GT(peak, 3800.0);  // the lightly damped mode overshoots (zeta about 0.1)
  run_to(plant, 11.0);
  // The integrating actuator leaves no steady-state error. Ten seconds after the step the
  // 2 Hz mode (decay e^{-1.3 t}) is gone; left is the tail of the slow pole pair of the
  // 5 s power filter, measured 0.71 kW (0.24 % of the step) and falling by ~18 % per second.
  EXPECT_NEAR(plant.electrical_power_kw(), 3800.0, 1.0);
  EXPECT_EQ(plant.params()[P::kPowerKw], 3800.0);
}

TEST(PlantFaults, LoadSetpointRampIsTrackedByTheGridConnectedSet) {
  GensetPlant plant(quiet(), changes({"op.power_kw=3800@t=1,ramp=10"}), 1, milliseconds(1));
  run_to(plant, 6.0);
  EXPECT_DOUBLE_EQ(plant.params()[P::kPowerKw], 3650.0);
  // The kW-controller tuning (R K T4 = 1) tracks a 30 kW/s ramp with about 1 kW of lag.
  EXPECT_NEAR(plant.electrical_power_kw(), 3650.0, 3.0);
  run_to(plant, 25.0);
  EXPECT_NEAR(plant.electrical_power_kw(), 3800.0, 0.5);
}

TEST(PlantFaults, IslandLoadChangeWorksAbruptAndRamped) {
  GensetPlant abrupt(quiet("stornoway_island"), changes({"load.step_pu=0.02@t=1"}), 1,
                     milliseconds(1));
  GensetPlant ramped(quiet("stornoway_island"), changes({"load.step_pu=0.02@t=1,ramp=10"}), 1,
                     milliseconds(1));
  run_to(ramped, 6.0);
  EXPECT_DOUBLE_EQ(ramped.params()[P::kLoadPu], 0.01);
  const double mid_kw = ramped.electrical_power_kw();
  EXPECT_GT(mid_kw, 3500.0 + 0.3 * 92.0);
  EXPECT_LT(mid_kw, 3500.0 + 0.7 * 92.0);
  run_to(abrupt, 40.0);
  run_to(ramped, 40.0);
  // The same new equilibrium: frequency down until governor droop and the load's D_L balance.
  EXPECT_LT(abrupt.measure().freq_hz, 49.99);
  EXPECT_NEAR(ramped.measure().freq_hz, abrupt.measure().freq_hz, 1e-4);
  EXPECT_NEAR(ramped.electrical_power_kw(), abrupt.electrical_power_kw(), 0.05);
}

TEST(PlantFaults, FractionalInjectorFaultGrowsTheCycleLine) {
  Params p = quiet();
  p.set(P::kEngRipple, 1.0, "test");
  const double f_cycle = p[P::kEngRpm] / 120.0;  // 5 Hz: once per four-stroke cycle
  GensetPlant plant(p, changes({"engine.injectors_out=1@t=1,ramp=20"}), 1, milliseconds(1));
  std::vector<double> lines;
  for (double t : {4.0, 9.0, 14.0, 19.0}) {  // one-second windows centred near t + 0.5
    run_to(plant, t);
    EXPECT_FALSE(plant.engine_closed_form());  // the engine lags ramp inside the ODE
    lines.push_back(line_kw(measured_kw(plant, 1.0), f_cycle));
  }
  run_to(plant, 40.0);
  EXPECT_TRUE(plant.engine_closed_form());  // back once the ramp has ended
  const double full = line_kw(measured_kw(plant, 2.0), f_cycle);
  std::cout << "5 Hz line during the ramp:";
  for (double a : lines) std::cout << " " << a;
  std::cout << " kW; after it " << full << " kW\n";
  for (std::size_t i = 1; i < lines.size(); ++i) EXPECT_GT(lines[i], lines[i - 1] + 15.0);
  EXPECT_GT(full, lines.back());
  // The line is linear in the lost fraction x (normalised by the delivering cylinders):
  // A(x) = A(1) x 11 / (12 - x); at the window centre of t = 9 .. 10, x = 0.425.
  const double x = 0.425;
  EXPECT_NEAR(lines[1], full * x * 11.0 / (12.0 - x), 0.03 * full);
}

TEST(PlantFaults, TwoInjectorsOutDipThenGovernorRestoresThePower) {
  Params p = quiet();
  p.set(P::kEngRipple, 1.0, "test");
  GensetPlant plant(p, changes({"engine.injectors_out=2@t=1"}), 1, milliseconds(1));
  double dip_kw = 1e9;
  double recovered_s = 0.0;  // last time outside 1 % of the setpoint
  for (int k = 1; k <= 40000; ++k) {
    plant.step();
    const double pe = plant.electrical_power_kw();
    dip_kw = std::min(dip_kw, pe);
    if (std::abs(pe - 3500.0) > 35.0) recovered_s = k * 1e-3 - 1.0;
  }
  ASSERT_FALSE(plant.measure().fault) << plant.last_error();
  const std::vector<double> tail = measured_kw(plant, 10.0);
  double mean_kw = 0.0;
  for (double y : tail) mean_kw += y / static_cast<double>(tail.size());
  std::cout << "injectors_out=2: dip to " << dip_kw << " kW, within 1 % after " << recovered_s
            << " s, 5 Hz line " << line_kw(tail, 5.0) << " kW, mean " << mean_kw << " kW\n";
  EXPECT_LT(dip_kw, 3500.0 - 2.0 / 12.0 * 3500.0);  // at least the lost torque, 583 kW
  EXPECT_LT(recovered_s, 30.0);
  EXPECT_NEAR(plant.electrical_power_kw(), 3500.0, 1.0);
  EXPECT_NEAR(mean_kw, 3500.0, 1.0);  // 10 s = 50 whole ripple cycles
}

}  // namespace
}  // namespace plantsim
