// Ramps of engine parameters against the plain plant: a ramp to the value a parameter
// already has hands the engine lags from the closed form (EnginePath) to the ODE and stops
// the look-ahead, which must not change the response beyond the solver tolerance; a real
// dead-time ramp moves the bias-to-power delay from the old dead time to the new one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/engine.hpp"
#include "plantsim/plant/genset_plant.hpp"

namespace plantsim {
namespace {

using std::chrono::milliseconds;

constexpr int kBiasEveryTicks = 10;  // 100 Hz bias writes on the 1 ms plant tick
constexpr double kBiasStdPct = 0.2;

Params quiet() {
  Params p = preset("stornoway");
  for (P id : {P::kMeasNoise, P::kMeasPickup, P::kMeasDrift, P::kMeasQuant, P::kEngRipple}) {
    p.set(id, 0.0, "test");
  }
  return p;
}

struct Trace {
  std::vector<double> bias_pct;
  std::vector<double> power_kw;
};

// The plant driven by the same seeded Gaussian bias sequence, one sample per tick.
Trace drive(const Params& p, const std::vector<std::string>& faults, double seconds) {
  std::vector<TimedChange> changes;
  for (const std::string& f : faults) changes.push_back(parse_change(f));
  GensetPlant plant(p, changes, 1, milliseconds(1));
  std::mt19937_64 rng(20240611);
  std::normal_distribution<double> gauss(0.0, kBiasStdPct);
  Trace out;
  double bias = 0.0;
  const long ticks = std::lround(seconds * 1000.0);
  for (long k = 0; k < ticks; ++k) {
    if (k % kBiasEveryTicks == 0) bias = gauss(rng);
    plant.set_bias_pct(bias);
    plant.step();
    if (plant.measure().fault) {
      ADD_FAILURE() << "tick " << k << ": " << plant.last_error();
      out.power_kw.resize(ticks, plant.measure().power_w / 1e3);  // the held output
      out.bias_pct.resize(ticks, bias);
      break;
    }
    out.bias_pct.push_back(bias);
    out.power_kw.push_back(plant.measure().power_w / 1e3);
  }
  return out;
}

double max_abs_diff(const Trace& a, const Trace& b, std::size_t from) {
  double d = 0.0;
  for (std::size_t k = from; k < a.power_kw.size(); ++k) {
    d = std::max(d, std::abs(a.power_kw[k] - b.power_kw[k]));
  }
  return d;
}

double rms(const Trace& a, std::size_t from) {
  double mean = 0.0, sq = 0.0;
  const auto n = static_cast<double>(a.power_kw.size() - from);
  for (std::size_t k = from; k < a.power_kw.size(); ++k) mean += a.power_kw[k] / n;
  for (std::size_t k = from; k < a.power_kw.size(); ++k) {
    sq += (a.power_kw[k] - mean) * (a.power_kw[k] - mean) / n;
  }
  return std::sqrt(sq);
}

// Lag (s) of the peak of the bias-to-power cross-correlation over samples [from, to), refined
// by a parabola through the peak and its neighbours: the small-signal delay a monitor fits
// moves with it.
double xcorr_peak_lag_s(const Trace& a, std::size_t from, std::size_t to) {
  constexpr std::size_t kMaxLag = 400;  // ms
  double mean_p = 0.0;
  for (std::size_t k = from; k < to; ++k) mean_p += a.power_kw[k] / static_cast<double>(to - from);
  std::vector<double> r(kMaxLag + 1, 0.0);
  for (std::size_t lag = 0; lag <= kMaxLag; ++lag) {
    for (std::size_t k = from; k + lag < to; ++k) {
      r[lag] += a.bias_pct[k] * (a.power_kw[k + lag] - mean_p);
    }
  }
  const auto peak = static_cast<std::size_t>(
      std::max_element(r.begin() + 1, r.end() - 1,
                       [](double x, double y) { return std::abs(x) < std::abs(y); }) -
      r.begin());
  const double ym = r[peak - 1], y0 = r[peak], yp = r[peak + 1];
  const double shift = 0.5 * (ym - yp) / (ym - 2.0 * y0 + yp);
  return (static_cast<double>(peak) + shift) * 1e-3;
}

constexpr double kRampStartS = 2.0;
constexpr double kRunS = 14.0;
constexpr auto kFrom = static_cast<std::size_t>(kRampStartS * 1000);
constexpr auto kTo = static_cast<std::size_t>(kRunS * 1000);

std::string fault(const char* name, double value, double t_s, double ramp_s) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%s=%.17g@t=%g,ramp=%g", name, value, t_s, ramp_s);
  return buf;
}

// At the preset's tolerances (rtol 1e-8, atol 2e-8 pu) the plain plant's power lies about
// 0.04 kW from a solution at rtol 1e-12 under this bias, and any ramp (one CVODE restart, as
// for meas.gain, which no equation reads) moves it by as much. With rtol 1e-12 and atol
// 2e-12 pu the same runs agree to about 3e-5 kW: kSameKw is 30 times that, a two-hundredth
// of the power's rms, and four decades below the 10 kW a dead time stepping to 0 gives.
constexpr double kSameKw = 1e-3;
constexpr double kSameKwPresetTol = 0.1;  // 2.5 times the preset tolerances' own error

Params tight() {
  Params p = quiet();
  p.set(P::kSolverRtol, 1e-12, "test");
  p.set(P::kSolverAtol, 2e-12, "test");
  return p;
}

void expect_ramp_to_own_value_changes_nothing(P id, double value) {
  const std::string name(spec(id).name);
  const std::string f = fault(name.c_str(), value, kRampStartS, 1800.0);
  for (const Params& p : {tight(), quiet()}) {
    const Trace plain = drive(p, {}, kRunS);
    const Trace ramped = drive(p, {f}, kRunS);
    const double diff = max_abs_diff(plain, ramped, 0);
    const double lag_plain = xcorr_peak_lag_s(plain, kFrom, kTo);
    const double lag_ramped = xcorr_peak_lag_s(ramped, kFrom, kTo);
    const bool preset_tol = p[P::kSolverRtol] > 1e-10;
    std::printf("%s (rtol %g): power rms %.3f kW, max |diff| %.3g kW, xcorr peak %.4f / %.4f ms\n",
                name.c_str(), p[P::kSolverRtol], rms(plain, kFrom), diff, 1e3 * lag_plain,
                1e3 * lag_ramped);
    EXPECT_GT(rms(plain, kFrom), 1.0);  // the bias does move the power
    EXPECT_LT(diff, preset_tol ? kSameKwPresetTol : kSameKw);
    EXPECT_NEAR(lag_ramped, lag_plain, preset_tol ? 2e-5 : 1e-6);
  }
}

TEST(PlantRampSameValue, DeadTimeRampedToItsOwnValueChangesNothing) {
  expect_ramp_to_own_value_changes_nothing(P::kEngDeadTime, dead_time_s(quiet()));
}

TEST(PlantRampSameValue, CombustionLagRampedToItsOwnValueChangesNothing) {
  expect_ramp_to_own_value_changes_nothing(P::kEngCombustionLag, quiet()[P::kEngCombustionLag]);
}

TEST(PlantRampSameValue, DeadTimeRampMovesTheDelayFromTheOldValueToTheNew) {
  const Params p = tight();
  const double td0 = dead_time_s(p);
  const double td1 = td0 + 0.025;
  const double ramp_s = 4.0;
  const std::string f = fault("engine.dead_time_s", td1, kRampStartS, ramp_s);
  // The dead time runs linearly from the old value to the new one (read back from the plant).
  GensetPlant plant(p, {parse_change(f)}, 1, milliseconds(1));
  for (double frac : {0.0, 0.25, 0.5, 0.75, 1.0, 1.25}) {
    while (plant.time_s() < kRampStartS + frac * ramp_s - 1e-9) plant.step();
    ASSERT_FALSE(plant.measure().fault) << plant.last_error();
    EXPECT_NEAR(dead_time_s(plant.params()), td0 + std::min(frac, 1.0) * (td1 - td0), 1e-12)
        << frac;
  }
  // No step at its start: the power leaves the plain plant's smoothly, in proportion to the
  // dead time gained (3e-5 kW after 10 ms, 0.06 us, 5e-3 kW after 50 ms); a dead time that
  // stepped by a tick would be off by more within the first 10 ms.
  const Trace plain = drive(p, {}, kRunS);
  const Trace ramped = drive(p, {f}, kRunS);
  const auto first = static_cast<std::size_t>(kFrom + 10);
  double start_diff = 0.0;
  for (std::size_t k = 0; k < first; ++k) {
    start_diff = std::max(start_diff, std::abs(ramped.power_kw[k] - plain.power_kw[k]));
  }
  EXPECT_LT(start_diff, kSameKw);
  // After the ramp the delay is that of a plant started with the new dead time.
  Params p1 = p;
  p1.set(P::kEngDeadTime, td1, "test");
  const Trace after = drive(p1, {}, kRunS);
  const auto end = static_cast<std::size_t>((kRampStartS + ramp_s + 1.0) * 1000);
  const double lag0 = xcorr_peak_lag_s(plain, end, kTo);
  const double lag_ramped = xcorr_peak_lag_s(ramped, end, kTo);
  const double lag1 = xcorr_peak_lag_s(after, end, kTo);
  std::printf(
      "dead time %.2f -> %.2f ms: first 10 ms max |diff| %.3g kW; xcorr peak %.3f ms "
      "(old), %.3f ms (ramped), %.3f ms (new)\n",
      1e3 * td0, 1e3 * td1, start_diff, 1e3 * lag0, 1e3 * lag_ramped, 1e3 * lag1);
  // The peak moves by more than the 25 ms (the loop's own phase changes with the delay).
  EXPECT_NEAR(lag_ramped, lag1, 1e-5);
  EXPECT_GT(lag_ramped - lag0, td1 - td0);
}

TEST(PlantRampSameValue, DeadTimeRampToZeroEndsOnTheFormula) {
  // engine.dead_time_s = 0 is the formula 30/N + 60/(n N): the ramp runs to its value.
  Params p = tight();
  const double formula = dead_time_s(p);
  p.set(P::kEngDeadTime, formula + 0.02, "test");
  GensetPlant plant(p, {parse_change("engine.dead_time_s=0@t=1,ramp=2")}, 1, milliseconds(1));
  while (plant.time_s() < 2.0 - 1e-9) plant.step();
  EXPECT_NEAR(dead_time_s(plant.params()), formula + 0.01, 1e-12);
  while (plant.time_s() < 3.5 - 1e-9) plant.step();
  ASSERT_FALSE(plant.measure().fault) << plant.last_error();
  EXPECT_EQ(plant.params()[P::kEngDeadTime], 0.0);
  EXPECT_NEAR(dead_time_s(plant.params()), formula, 1e-15);
}

}  // namespace
}  // namespace plantsim
