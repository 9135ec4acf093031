#include "rig/session/supervisor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

namespace rig::session {
namespace {

constexpr double kP0 = 3500.0;

SupervisorConfig base_config() {
  SupervisorConfig c;
  c.p0_kw = kP0;  // band 105 kW
  c.baseline_bias_pct = 0.2;
  c.clamp_pct = 2.0;
  c.ramp_rate_pct_per_s = 1.0;  // 0.01 % per 10 ms tick
  c.dt_s = 0.01;
  c.stale_ticks = 3;
  return c;
}

drivers::Sample good_sample(std::uint16_t counter, double power_kw = kP0) {
  drivers::Sample s;
  s.power_kw = power_kw;
  s.counter = counter;
  s.status = drivers::kRunning | drivers::kBreakerClosed | drivers::kBiasActive;
  return s;
}

TEST(SupervisorConfig, BandAboveThreePercentNeedsOverride) {
  SupervisorConfig c = base_config();
  c.band_fraction = 0.031;
  EXPECT_THROW(Supervisor{c}, SupervisorConfigError);
  try {
    validate(c);
  } catch (const SupervisorConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("band_override"), std::string::npos) << e.what();
  }
  c.band_override = true;
  Supervisor s(c);
  EXPECT_TRUE(s.band_overridden());
  EXPECT_NEAR(s.config().band_kw(), 108.5, 1e-9);
  c.band_override = false;
  c.band_fraction = 0.02;  // lowering is always allowed
  EXPECT_FALSE(Supervisor(c).band_overridden());
}

TEST(SupervisorConfig, RejectsNonsense) {
  const std::vector<std::function<void(SupervisorConfig&)>> breakers = {
      [](SupervisorConfig& c) { c.p0_kw = 0.0; },
      [](SupervisorConfig& c) { c.p0_kw = std::numeric_limits<double>::quiet_NaN(); },
      [](SupervisorConfig& c) { c.band_fraction = 0.0; },
      [](SupervisorConfig& c) { c.clamp_pct = -1.0; },
      [](SupervisorConfig& c) { c.baseline_bias_pct = 2.5; },  // outside the clamp
      [](SupervisorConfig& c) { c.ramp_rate_pct_per_s = 0.0; },
      [](SupervisorConfig& c) { c.stale_ticks = 0; },
      [](SupervisorConfig& c) { c.backoff.start_fraction = 0.95; },
  };
  for (std::size_t i = 0; i < breakers.size(); ++i) {
    SupervisorConfig c = base_config();
    breakers[i](c);
    EXPECT_THROW(validate(c), SupervisorConfigError) << "case " << i;
  }
  EXPECT_NO_THROW(validate(base_config()));
}

// Runs a started supervisor at full scale with a constant request so that the bias sits
// away from the baseline, then returns the output of the last good tick.
struct Running {
  Supervisor sup{base_config()};
  std::uint16_t counter = 0;
  SupervisorOutput last;
  explicit Running(double request_pct = 0.8) {
    sup.start();
    for (int i = 0; i < 1100; ++i) last = sup.tick(good_sample(++counter), request_pct);
  }
};

struct TripCase {
  const char* name;
  TripCause cause;
  std::function<SupervisorOutput(Running&)> fault;  // the faulty tick
};

TEST(SupervisorTrip, EveryCauseTripsInOneTickAndZeroesTheExcitation) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<TripCase> cases = {
      {"above band", TripCause::kOutOfBand,
       [](Running& r) { return r.sup.tick(good_sample(++r.counter, kP0 + 105.1), 0.8); }},
      {"below band", TripCause::kOutOfBand,
       [](Running& r) { return r.sup.tick(good_sample(++r.counter, kP0 - 105.1), 0.8); }},
      {"NaN power", TripCause::kNotFinite,
       [nan](Running& r) { return r.sup.tick(good_sample(++r.counter, nan), 0.8); }},
      {"Inf power", TripCause::kNotFinite,
       [inf](Running& r) { return r.sup.tick(good_sample(++r.counter, -inf), 0.8); }},
      {"missing", TripCause::kMissingSample, [](Running& r) { return r.sup.tick_missing(0.8); }},
      {"timeout", TripCause::kMissingSample,
       [](Running& r) {
         drivers::LinkResult<drivers::Sample> read(
             drivers::LinkError{drivers::LinkErrorKind::kTimeout, "input 0", "timed out"});
         return r.sup.tick(read, 0.8);
       }},
      {"link lost", TripCause::kLinkError,
       [](Running& r) {
         drivers::LinkResult<drivers::Sample> read(
             drivers::LinkError{drivers::LinkErrorKind::kLinkLost, "input 0", "reset by peer"});
         return r.sup.tick(read, 0.8);
       }},
      {"plant fault", TripCause::kGovernorStatus,
       [](Running& r) {
         auto s = good_sample(++r.counter);
         s.status |= drivers::kPlantFault;
         return r.sup.tick(s, 0.8);
       }},
      {"heartbeat lost", TripCause::kGovernorStatus,
       [](Running& r) {
         auto s = good_sample(++r.counter);
         s.status |= drivers::kHeartbeatLost;
         return r.sup.tick(s, 0.8);
       }},
      {"not running", TripCause::kGovernorStatus,
       [](Running& r) {
         auto s = good_sample(++r.counter);
         s.status &= static_cast<std::uint16_t>(~drivers::kRunning);
         return r.sup.tick(s, 0.8);
       }},
      {"stale counter", TripCause::kStaleSample,
       [](Running& r) {
         // Two unchanged ticks are tolerated (stale_ticks = 3); the third trips.
         for (int i = 0; i < 2; ++i) {
           const auto o = r.sup.tick(good_sample(r.counter), 0.8);
           EXPECT_FALSE(r.sup.tripped());
           r.last = o;
         }
         return r.sup.tick(good_sample(r.counter), 0.8);
       }},
      {"write failure", TripCause::kLinkError,
       [](Running& r) {
         r.sup.trip(TripCause::kLinkError, "holding 0: broken pipe");
         return r.sup.tick(good_sample(++r.counter), 0.8);
       }},
  };
  for (const TripCase& c : cases) {
    SCOPED_TRACE(c.name);
    Running r;
    ASSERT_EQ(r.last.state, SupervisorState::kRunning);
    ASSERT_DOUBLE_EQ(r.last.scale, 1.0);
    ASSERT_NEAR(r.last.bias_pct, 1.0, 1e-12);  // 0.2 baseline + 0.8 excitation
    const SupervisorOutput out = c.fault(r);
    EXPECT_EQ(out.state, SupervisorState::kTripped);
    EXPECT_EQ(out.trip_cause, c.cause);
    EXPECT_EQ(out.scale, 0.0);
    // The request no longer reaches the bias: it moves one ramp step toward the baseline.
    EXPECT_NEAR(out.bias_pct, r.last.bias_pct - 0.01, 1e-12);
    ASSERT_TRUE(r.sup.trip_record().has_value());
    EXPECT_FALSE(r.sup.trip_record()->text.empty());
    // Latched: a healthy sample and an absurd request change nothing, the first cause stays.
    const SupervisorOutput next = r.sup.tick(good_sample(++r.counter, kP0 + 500.0), 1e9);
    EXPECT_EQ(next.trip_cause, c.cause);
    EXPECT_NEAR(next.bias_pct, out.bias_pct - 0.01, 1e-12);
  }
}

TEST(SupervisorRamp, ReturnsToBaselineAtTheConfiguredRateWithoutOvershoot) {
  for (double request : {1.5, -1.9}) {
    SCOPED_TRACE(request);
    Running r(request);
    const double start = r.last.bias_pct;
    r.sup.trip(TripCause::kExternal, "operator abort");
    double prev = start;
    int ticks = 0;
    SupervisorOutput out;
    do {
      out = r.sup.tick(good_sample(++r.counter), request);
      ++ticks;
      EXPECT_LE(std::abs(out.bias_pct - prev), 0.01 + 1e-12);  // 1 %/s at 10 ms
      // Monotone toward the baseline, never beyond it.
      EXPECT_LE(std::abs(out.bias_pct - 0.2), std::abs(prev - 0.2) + 1e-12);
      EXPECT_GE((out.bias_pct - 0.2) * (start - 0.2), -1e-12);
      prev = out.bias_pct;
    } while (!r.sup.done() && ticks < 1000);
    EXPECT_DOUBLE_EQ(out.bias_pct, 0.2);
    EXPECT_EQ(out.state, SupervisorState::kDone);
    // |start - baseline| / step ticks to reach, rounded up, plus the tick reporting done.
    EXPECT_NEAR(ticks, std::ceil(std::abs(start - 0.2) / 0.01 - 1e-9), 1.0);
    EXPECT_EQ(r.sup.trip_record()->cause, TripCause::kExternal);
  }
}

TEST(SupervisorRamp, NormalFinishRampsDownWithoutTrip) {
  Running r;
  r.sup.finish();
  SupervisorOutput out;
  int ticks = 0;
  while (!r.sup.done() && ticks < 1000) {
    out = r.sup.tick(good_sample(++r.counter), 0.8);
    if (!r.sup.done()) {
      EXPECT_EQ(out.state, SupervisorState::kRampingDown);
    }
    ++ticks;
  }
  EXPECT_EQ(ticks, 80);  // (1.0 - 0.2) / 0.01
  EXPECT_DOUBLE_EQ(out.bias_pct, 0.2);
  EXPECT_EQ(out.trip_cause, TripCause::kNone);
  EXPECT_FALSE(r.sup.tripped());
}

TEST(SupervisorClamp, HoldsForAbsurdRequests) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  Running r;
  const std::vector<std::pair<double, double>> cases = {{1e9, 2.0}, {-1e9, -2.0}, {nan, 0.2},
                                                        {inf, 2.0}, {-inf, -2.0}, {1.0, 1.2}};
  for (const auto& [request, expected] : cases) {
    const SupervisorOutput out = r.sup.tick(good_sample(++r.counter), request);
    EXPECT_DOUBLE_EQ(out.bias_pct, expected) << "request " << request;
    EXPECT_DOUBLE_EQ(out.excitation_pct, expected - 0.2);
    EXPECT_FALSE(r.sup.tripped());
  }
  // The clamp is absolute, so it also holds against a baseline near its edge.
  SupervisorConfig c = base_config();
  c.baseline_bias_pct = 1.9;
  Supervisor s(c);
  s.start();
  SupervisorOutput out;
  for (std::uint16_t i = 1; i < 1100; ++i) out = s.tick(good_sample(i), 5.0);
  EXPECT_DOUBLE_EQ(out.bias_pct, 2.0);
}

TEST(SupervisorLifecycle, IdleSoftStartAndHeartbeat) {
  Supervisor s(base_config());
  std::uint16_t counter = 0;
  SupervisorOutput out = s.tick(good_sample(++counter), 1.0);
  EXPECT_EQ(out.state, SupervisorState::kIdle);
  EXPECT_DOUBLE_EQ(out.bias_pct, 0.2);  // idle ignores the request
  EXPECT_EQ(out.heartbeat, 1);
  s.start();
  double prev_scale = 0.0;
  for (int i = 1; i <= 1000; ++i) {
    out = s.tick(good_sample(++counter), 1.0);
    // Soft start: the scale rises 0.1 per second, 0.001 per tick.
    EXPECT_NEAR(out.scale, std::min(1.0, prev_scale + 0.001), 1e-12);
    prev_scale = out.scale;
    EXPECT_EQ(out.heartbeat, static_cast<std::uint16_t>(i + 1));
  }
  EXPECT_NEAR(out.scale, 1.0, 1e-12);
  // The heartbeat keeps counting while tripped and wraps at 16 bits.
  s.trip(TripCause::kExternal, "test");
  for (int i = 0; i < 70000; ++i) out = s.tick(good_sample(++counter), 0.0);
  EXPECT_EQ(out.heartbeat, static_cast<std::uint16_t>(1001 + 70000));
  EXPECT_EQ(out.state, SupervisorState::kDone);
}

TEST(SupervisorBackoff, EnvelopeSeesTheFreeSwingOfTheModeAndIgnoresPickUp) {
  const SupervisorConfig c = base_config();  // resonance 2 Hz, dt 10 ms
  DeviationEnvelope env(c.backoff, c.dt_s);
  // A 2 Hz swing of 50 kW: after a few cycles the envelope reads ~50 kW at every sample, also
  // at the zero crossings of d where a peak detector would still be waiting.
  double lo = 1e9, hi = 0.0;
  for (int k = 0; k < 800; ++k) {
    const double d = 50.0 * std::sin(2.0 * std::numbers::pi * 2.0 * k * c.dt_s);
    const double e = env.update(d);
    if (k > 400) {
      lo = std::min(lo, e);
      hi = std::max(hi, e);
    }
  }
  EXPECT_GT(lo, 0.9 * 50.0 * 0.75);  // filter gain at f_r/3 cut-off is ~0.99; release 2 s
  EXPECT_LT(hi, 1.1 * 50.0);
  // The first quarter cycle of a new swing: the envelope leads |d|.
  DeviationEnvelope fresh(c.backoff, c.dt_s);
  double e = 0.0, d = 0.0;
  for (int k = 0; k <= 6; ++k) {
    d = 50.0 * std::sin(2.0 * std::numbers::pi * 2.0 * k * c.dt_s);
    e = fresh.update(d);
  }
  EXPECT_GT(e, 1.05 * std::abs(d));
  // 40 Hz pick-up of 10 kW is filtered before the derivative: envelope stays near 10 kW.
  DeviationEnvelope pickup(c.backoff, c.dt_s);
  double worst = 0.0;
  for (int k = 0; k < 400; ++k) {
    worst =
        std::max(worst, pickup.update(10.0 * std::sin(2.0 * std::numbers::pi * 40.0 * k * c.dt_s)));
  }
  EXPECT_LT(worst, 12.0);
}

TEST(SupervisorBackoff, ScalesDownAboveStartFractionAndRecoversSlowly) {
  SupervisorConfig c = base_config();
  c.backoff.resonance_hz = 0.0;  // peak hold only, so the scale follows |d| exactly
  Running r(0.5);
  r.sup = Supervisor(c);
  r.sup.start();
  for (int i = 0; i < 1100; ++i) r.last = r.sup.tick(good_sample(++r.counter), 0.5);
  // A deviation of 75 % of the band (78.75 kW): halfway between 60 % and 90 % -> scale 0.5,
  // reached at the fall rate (5 /s: 0.05 per tick), so the bias never steps.
  SupervisorOutput out;
  double prev_scale = 1.0;
  for (int i = 0; i < 10; ++i) {
    out = r.sup.tick(good_sample(++r.counter, kP0 + 78.75), 0.5);
    EXPECT_EQ(out.state, SupervisorState::kBackingOff);
    EXPECT_NEAR(out.scale, prev_scale - 0.05, 1e-9) << "tick " << i;
    prev_scale = out.scale;
  }
  EXPECT_NEAR(out.scale, 0.5, 1e-9);
  EXPECT_NEAR(out.bias_pct, 0.2 + 0.25, 1e-9);
  out = r.sup.tick(good_sample(++r.counter, kP0 + 78.75), 0.5);
  EXPECT_NEAR(out.scale, 0.5, 1e-9);  // and holds there
  // Back at P0 the envelope decays with 2 s and the scale may rise only 0.001 per tick.
  double prev = out.scale;
  for (int i = 0; i < 100; ++i) {
    out = r.sup.tick(good_sample(++r.counter), 0.5);
    EXPECT_LE(out.scale, prev + 0.001 + 1e-12);
    prev = out.scale;
  }
  EXPECT_LT(out.scale, 0.65);
  EXPECT_FALSE(r.sup.tripped());
}

}  // namespace
}  // namespace rig::session
