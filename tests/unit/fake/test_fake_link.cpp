// The fake governor link behaves as drivers/fake/fake_link.hpp specifies: plant response (gain,
// resonance, dead time), governor rules (quantisation, clamp, heartbeat), every fault mode, the
// write log, and determinism for a seed.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "drivers/fake/fake_link.hpp"

namespace drivers::fake {
namespace {

FakePlant quiet() {
  FakePlant p;
  p.noise_kw = 0.0;
  return p;
}

LinkOptions lockstep() {
  LinkOptions o;
  o.lockstep = true;
  return o;
}

void start(FakeGovernorLink& link) {
  ASSERT_TRUE(link.configure());
  ASSERT_TRUE(link.activate());
}

// One lockstep exchange: write, advance one tick, read.
Sample cycle(FakeGovernorLink& link, double bias_pct) {
  EXPECT_TRUE(link.write(bias_pct));
  EXPECT_TRUE(link.advance(1));
  auto r = link.read();
  EXPECT_TRUE(r) << (r ? "" : r.error().message());
  return r ? *r : Sample{};
}

// Amplitude of the component at f_hz of y (whole periods).
double amplitude(const std::vector<double>& y, double f_hz, double dt_s) {
  double a = 0.0, b = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    const double w = 2.0 * std::numbers::pi * f_hz * static_cast<double>(k) * dt_s;
    a += y[k] * std::sin(w);
    b += y[k] * std::cos(w);
  }
  return 2.0 * std::hypot(a, b) / static_cast<double>(y.size());
}

TEST(FakeLink, StepResponseSettlesAtGainWithSecondOrderOvershoot) {
  FakeGovernorLink link(quiet(), {}, lockstep());
  start(link);
  double peak = 0.0, last = 0.0;
  for (int k = 0; k < 1000; ++k) {
    last = cycle(link, 1.0).power_kw - 3500.0;
    peak = std::max(peak, last);
  }
  EXPECT_NEAR(last, 46.0, 0.01);
  const double overshoot = std::exp(-std::numbers::pi * 0.1 / std::sqrt(1.0 - 0.01));
  EXPECT_NEAR(peak, 46.0 * (1.0 + overshoot), 0.5);
}

TEST(FakeLink, SineAtTheModeIsAmplifiedByOneOverTwoZeta) {
  FakeGovernorLink link(quiet(), {}, lockstep());
  start(link);
  std::vector<double> y;
  for (int k = 0; k < 2000; ++k) {  // 10 s to settle, then 20 periods of 2 Hz
    const double bias = 0.1 * std::sin(2.0 * std::numbers::pi * 2.0 * link.t_s());
    const double p = cycle(link, bias).power_kw - 3500.0;
    if (k >= 1000) y.push_back(p);
  }
  EXPECT_NEAR(amplitude(y, 2.0, 0.01), 46.0 * 0.1 / (2.0 * 0.1), 0.02 * 23.0);
}

TEST(FakeLink, DeadTimeDelaysTheFirstResponse) {
  for (double fn : {0.0, 2.0}) {
    FakePlant plant = quiet();
    plant.fn_hz = fn;
    FakeGovernorLink link(plant, {}, lockstep());
    start(link);
    std::vector<Sample> s;
    for (int k = 0; k < 10; ++k) s.push_back(cycle(link, 1.0));  // first write at t = 0
    for (int k = 0; k < 6; ++k) EXPECT_EQ(s[k].power_kw, 3500.0) << "fn " << fn << " k " << k;
    EXPECT_NEAR(s[6].plant_time_s, 0.06 + 0.01, 1e-12);
    EXPECT_GT(s[6].power_kw, 3500.0) << "fn " << fn;
    if (fn == 0.0) {
      EXPECT_NEAR(s[6].power_kw, 3546.0, 1e-9);
    }
  }
}

TEST(FakeLink, QuantisesHoldsAndClampsTheBias) {
  FakeGovernorLink link(quiet(), {}, lockstep());
  start(link);
  Sample s = cycle(link, 0.12345);
  EXPECT_DOUBLE_EQ(link.held_bias_pct(), 0.123);
  EXPECT_DOUBLE_EQ(s.bias_echo_pct, 0.123);
  EXPECT_EQ(s.status, kRunning | kBreakerClosed | kBiasActive);
  s = cycle(link, 8.0);
  EXPECT_DOUBLE_EQ(link.held_bias_pct(), 8.0);
  EXPECT_DOUBLE_EQ(link.applied_bias_pct(), 5.0);
  EXPECT_DOUBLE_EQ(s.bias_echo_pct, 5.0);
  EXPECT_DOUBLE_EQ(*link.read_held_bias(), 5.0);  // read back: what the governor applies
  EXPECT_EQ(link.uri(), "fake://governor");
}

TEST(FakeLink, WriteLogRecordsActivateWritesAndTheDeactivateRamp) {
  FakeGovernorLink link(quiet(), {}, lockstep());
  start(link);
  for (int k = 0; k < 5; ++k) cycle(link, 1.0);
  ASSERT_TRUE(link.deactivate());
  const auto& w = link.writes();
  const auto steps = static_cast<std::size_t>(std::ceil(1.0 / (2.0 * 0.02)));  // 25: LinkBase
  ASSERT_EQ(w.size(), 1u + 5u + steps + 1u);  // activate, writes, ramp, disable
  EXPECT_TRUE(w.front().enable && w.front().accepted && w.front().bias_pct == 0.0);
  for (int k = 1; k <= 5; ++k) EXPECT_DOUBLE_EQ(w[k].bias_pct, 1.0);
  for (std::size_t k = 6; k < w.size(); ++k) {
    EXPECT_LE(w[k - 1].bias_pct - w[k].bias_pct, 0.04 + 1e-9) << k;
    EXPECT_GE(w[k - 1].bias_pct - w[k].bias_pct, 0.0) << k;
    EXPECT_TRUE(w[k].accepted);
  }
  EXPECT_NEAR(w[7].t_s - w[6].t_s, 20 * 0.01, 1e-9);  // ramp_ticks_per_step ticks per step
  EXPECT_TRUE(w[w.size() - 2].enable);
  EXPECT_FALSE(w.back().enable);
  EXPECT_EQ(w.back().bias_pct, 0.0);
  EXPECT_FALSE(link.enabled());
  EXPECT_EQ(link.applied_bias_pct(), 0.0);
  EXPECT_EQ(link.held_bias_pct(), 0.0);
}

TEST(FakeLink, HeartbeatDropsTheBiasHalfASecondAfterTheLastWrite) {
  FakeGovernorLink link(quiet(), {}, lockstep());
  start(link);
  cycle(link, 1.0);  // written at t = 0
  ASSERT_TRUE(link.advance(49));
  Sample s = *link.read();  // t = 0.5: still alive
  EXPECT_TRUE(s.status & kBiasActive);
  EXPECT_DOUBLE_EQ(s.bias_echo_pct, 1.0);
  ASSERT_TRUE(link.advance(1));
  s = *link.read();  // t = 0.51: lost
  EXPECT_EQ(s.status, kRunning | kBreakerClosed | kHeartbeatLost);
  EXPECT_EQ(s.bias_echo_pct, 0.0);
  EXPECT_EQ(link.applied_bias_pct(), 0.0);
  EXPECT_EQ(link.held_bias_pct(), 1.0);
  s = cycle(link, 1.0);  // the next write re-applies
  EXPECT_EQ(s.status, kRunning | kBreakerClosed | kBiasActive);
  EXPECT_EQ(link.applied_bias_pct(), 1.0);

  FakeFaults off;
  off.heartbeat_rule = false;
  FakeGovernorLink patient(quiet(), off, lockstep());
  start(patient);
  cycle(patient, 1.0);
  ASSERT_TRUE(patient.advance(500));
  EXPECT_EQ(patient.read()->status, kRunning | kBreakerClosed | kBiasActive);
}

TEST(FakeLink, IgnoredOrLateHonouredBias) {
  FakeFaults ignore;
  ignore.ignore_bias = true;
  FakeGovernorLink deaf(quiet(), ignore, lockstep());
  start(deaf);
  for (int k = 0; k < 100; ++k) {
    const Sample s = cycle(deaf, 1.0);
    ASSERT_EQ(s.status, kRunning | kBreakerClosed);
    ASSERT_EQ(s.bias_echo_pct, 0.0);
    ASSERT_EQ(s.power_kw, 3500.0);
  }
  EXPECT_TRUE(deaf.enabled());

  FakeFaults late;
  late.honour_after_s = 0.2;
  FakeGovernorLink slow(quiet(), late, lockstep());
  start(slow);
  for (int k = 0; k < 40; ++k) {
    const Sample s = cycle(slow, 1.0);
    const bool honoured = s.plant_time_s >= 0.2 - 1e-9;
    EXPECT_EQ((s.status & kBiasActive) != 0, honoured) << s.plant_time_s;
    EXPECT_EQ(s.bias_echo_pct, honoured ? 1.0 : 0.0) << s.plant_time_s;
  }
}

TEST(FakeLink, EchoScaleAndLyingEcho) {
  for (bool lying : {false, true}) {
    FakeFaults f;
    (lying ? f.apply_scale : f.echo_scale) = 0.5;
    FakeGovernorLink link(quiet(), f, lockstep());
    start(link);
    Sample s;
    for (int k = 0; k < 1000; ++k) s = cycle(link, 1.0);
    EXPECT_DOUBLE_EQ(s.bias_echo_pct, lying ? 1.0 : 0.5);
    EXPECT_DOUBLE_EQ(link.applied_bias_pct(), 0.5);
    EXPECT_NEAR(s.power_kw, 3500.0 + 23.0, 0.01);
  }
}

TEST(FakeLink, RefusedWritesApplyNothingLateWritesApply) {
  FakeFaults refuse;
  refuse.refuse_writes_after_s = 0.1;
  FakeGovernorLink link(quiet(), refuse, lockstep());
  start(link);
  for (int k = 0; k < 10; ++k) cycle(link, 1.0);
  auto r = link.write(2.0);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kModbusException);
  EXPECT_EQ(link.held_bias_pct(), 1.0);
  EXPECT_FALSE(link.writes().back().accepted);
  EXPECT_EQ(link.writes().back().bias_pct, 2.0);
  EXPECT_NEAR(link.writes().back().t_s, 0.1, 1e-9);

  FakeFaults late;
  late.late_writes_after_s = 0.1;
  FakeGovernorLink laggy(quiet(), late, lockstep());
  start(laggy);
  for (int k = 0; k < 10; ++k) cycle(laggy, 1.0);
  r = laggy.write(2.0);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kTimeout);
  EXPECT_EQ(laggy.held_bias_pct(), 2.0);
  EXPECT_EQ(laggy.applied_bias_pct(), 2.0);
  EXPECT_TRUE(laggy.writes().back().accepted);
}

TEST(FakeLink, DroppedLinkFailsEveryCallUntilAReconnectIsAccepted) {
  FakeFaults f;
  f.drop_after_s = 0.1;
  f.reconnects_refused = 2;
  FakeGovernorLink link(quiet(), f, lockstep());
  start(link);
  for (int k = 0; k < 9; ++k) cycle(link, 1.5);
  ASSERT_TRUE(link.write(1.5));
  ASSERT_TRUE(link.advance(1));  // t = 0.1
  const auto n = link.writes().size();
  EXPECT_EQ(link.read().error().kind, LinkErrorKind::kLinkLost);
  EXPECT_EQ(link.write(0.0).error().kind, LinkErrorKind::kLinkLost);
  EXPECT_EQ(link.advance(1).error().kind, LinkErrorKind::kLinkLost);
  EXPECT_EQ(link.read_held_bias().error().kind, LinkErrorKind::kLinkLost);
  EXPECT_EQ(link.writes().size(), n);  // the governor saw nothing
  EXPECT_EQ(link.configure().error().kind, LinkErrorKind::kLinkLost);
  EXPECT_EQ(link.configure().error().kind, LinkErrorKind::kLinkLost);
  EXPECT_EQ(link.read().error().kind, LinkErrorKind::kLinkLost);
  ASSERT_TRUE(link.configure());
  EXPECT_EQ(link.configure_calls(), 4);
  EXPECT_EQ(link.held_bias_pct(), 1.5);    // the governor kept its registers
  EXPECT_EQ(*link.read_held_bias(), 1.5);  // and applies the bias still (no heartbeat loss yet)
  EXPECT_TRUE(link.enabled());
  ASSERT_TRUE(link.deactivate());
  EXPECT_FALSE(link.enabled());
  EXPECT_EQ(link.held_bias_pct(), 0.0);
  EXPECT_GT(link.writes().size(), n + 2);
}

TEST(FakeLink, FrozenCounterIsStaleInBothClocks) {
  FakeFaults f;
  f.freeze_counter_after_s = 0.05;
  FakeGovernorLink link(quiet(), f, lockstep());
  start(link);
  for (int k = 0; k < 5; ++k) cycle(link, 0.0);  // up to t = 0.05
  ASSERT_TRUE(link.advance(1));
  EXPECT_EQ(link.read().error().kind, LinkErrorKind::kStale);

  FakeGovernorLink realtime(quiet(), f);  // stale after stale_timeout (100 ms) of plant time
  ASSERT_TRUE(realtime.configure());
  double failed_at = 0.0;
  for (int k = 0; k < 30 && failed_at == 0.0; ++k) {
    auto r = realtime.read();
    if (!r) {
      EXPECT_EQ(r.error().kind, LinkErrorKind::kStale);
      failed_at = realtime.t_s();
    }
  }
  EXPECT_NEAR(failed_at, 0.16, 1e-9);
}

TEST(FakeLink, NanPowerPowerJumpAndReadTimeout) {
  FakeFaults f;
  f.nan_power_after_s = 0.05;
  f.power_jump_after_s = 0.03;
  f.power_jump_kw = 100.0;
  f.read_timeout_after_s = 0.08;
  FakeGovernorLink link(quiet(), f, lockstep());
  start(link);
  EXPECT_EQ(cycle(link, 0.0).power_kw, 3500.0);  // 0.01
  EXPECT_EQ(cycle(link, 0.0).power_kw, 3500.0);
  EXPECT_EQ(cycle(link, 0.0).power_kw, 3600.0);  // 0.03
  EXPECT_EQ(cycle(link, 0.0).power_kw, 3600.0);
  EXPECT_TRUE(std::isnan(cycle(link, 0.0).power_kw));  // 0.05
  for (int k = 0; k < 2; ++k) cycle(link, 0.0);
  ASSERT_TRUE(link.write(0.0));  // writes still pass
  ASSERT_TRUE(link.advance(1));
  EXPECT_EQ(link.read().error().kind, LinkErrorKind::kTimeout);  // 0.08
}

TEST(FakeLink, RealtimeReadAdvancesOneSampleAndAdvanceIsIgnored) {
  FakeGovernorLink link(quiet());
  ASSERT_TRUE(link.configure());
  for (std::uint16_t k = 1; k <= 3; ++k) {
    auto s = link.read();
    ASSERT_TRUE(s);
    EXPECT_EQ(s->counter, k);
    EXPECT_NEAR(s->plant_time_s, 0.01 * k, 1e-12);
    EXPECT_TRUE(link.advance(10));
  }
}

TEST(FakeLink, CallsBeforeConfigureAreConfigErrors) {
  FakeGovernorLink link;
  EXPECT_EQ(link.read().error().kind, LinkErrorKind::kConfig);
  EXPECT_EQ(link.write(1.0).error().kind, LinkErrorKind::kConfig);
  EXPECT_EQ(link.advance(1).error().kind, LinkErrorKind::kConfig);
  EXPECT_EQ(link.read_held_bias().error().kind, LinkErrorKind::kConfig);
  EXPECT_TRUE(link.writes().empty());
  EXPECT_EQ(link.t_s(), 0.0);
}

std::vector<double> run(std::uint64_t seed) {
  FakePlant plant;
  plant.seed = seed;
  FakeGovernorLink link(plant);  // realtime
  EXPECT_TRUE(link.configure());
  EXPECT_TRUE(link.activate());
  std::vector<double> p;
  for (int k = 0; k < 2000; ++k) {
    EXPECT_TRUE(link.write(0.5 * std::sin(0.3 * k)));
    p.push_back(link.read()->power_kw);
  }
  return p;
}

TEST(FakeLink, SameSeedSameSamplesAndNoiseRms) {
  const auto a = run(7);
  EXPECT_EQ(a, run(7));
  EXPECT_NE(a, run(8));
  FakeGovernorLink link;
  ASSERT_TRUE(link.configure());
  double sum2 = 0.0;
  for (int k = 0; k < 2000; ++k) sum2 += std::pow(link.read()->power_kw - 3500.0, 2);
  EXPECT_NEAR(std::sqrt(sum2 / 2000.0), 5.0, 0.3);
}

}  // namespace
}  // namespace drivers::fake
