// The monitor's core on synthetic records (synthetic_set.hpp): decisions, names, the
// designed false-alarm rate of the CUSUM, event shapes and the tracked-parameter registry.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rig/monitor/event_shape.hpp"
#include "rig/monitor/monitor.hpp"
#include "rig/monitor/sequential_test.hpp"
#include "rig/monitor/tracked_parameters.hpp"
#include "synthetic_set.hpp"

namespace rig::monitor {
namespace {

using testing::generate;
using testing::sopdt;
using testing::SyntheticChange;
using testing::SyntheticSet;

struct RunResult {
  std::vector<AlarmRecord> alarms;
  std::vector<MonitorEvent> events;
};

// Feeds a record to a monitor whose baseline is the unchanged set; re-baselines when asked
// (as the session does after a level event).
RunResult run(const SyntheticSet& set, const SyntheticChange& change, double duration_s) {
  const model::TransferFunction g = sopdt();
  const auto rec = generate(set, g, duration_s, change);
  MonitorSettings s;
  s.p0_kw = set.p0_kw;
  Monitor m(g, s);
  m.resume(set.p0_kw);
  RunResult out;
  for (std::size_t k = 0; k < rec.t_s.size(); ++k) {
    if (m.wants_rebaseline()) m.resume(rec.y_kw[k]);
    m.push(rec.t_s[k], rec.u_pct[k], rec.y_kw[k], set.speed_rpm);
    for (auto& a : m.take_alarms()) out.alarms.push_back(a);
    for (auto& e : m.take_events()) out.events.push_back(e);
  }
  return out;
}

std::string causes(const RunResult& r) {
  std::string s;
  for (const auto& a : r.alarms) {
    s += a.cause + " @" + std::to_string(a.t_s) + " " + a.evidence_json + "; ";
  }
  for (const auto& e : r.events)
    s += "\n  event " + e.kind + " @" + std::to_string(e.t_s) + ": " + e.text;
  return s;
}

TEST(MonitorCore, NoAlarmOnAFaultFreeRecord) {
  for (std::uint64_t seed : {11u, 12u}) {
    SyntheticSet set;
    set.seed = seed;
    const RunResult r = run(set, {}, 3600.0);
    EXPECT_TRUE(r.alarms.empty()) << "seed " << seed << ": " << causes(r);
    bool learnt = false;
    for (const auto& e : r.events) learnt = learnt || e.kind == "learnt";
    EXPECT_TRUE(learnt);
  }
}

TEST(MonitorCore, GainLossWithTheHalfOrderLineIsAnInjectorLoss) {
  SyntheticSet set;
  SyntheticChange c;
  c.at_s = 900.0;
  c.model = sopdt(46.3 * 10.0 / 12.0);
  c.line_kw = 4.0;
  const RunResult r = run(set, c, 1500.0);
  ASSERT_FALSE(r.alarms.empty());
  EXPECT_EQ(r.alarms.front().cause, "injector/cylinder loss") << causes(r);
  EXPECT_EQ(r.alarms.front().fault_class, "multiplicative");
  EXPECT_LT(r.alarms.front().t_s - c.at_s, 300.0);
}

TEST(MonitorCore, GainRiseWithoutLineIsTheTransducerGain) {
  SyntheticSet set;
  SyntheticChange c;
  c.at_s = 900.0;
  c.model = sopdt(46.3 * 1.1);
  const RunResult r = run(set, c, 1500.0);
  ASSERT_FALSE(r.alarms.empty());
  EXPECT_EQ(r.alarms.front().cause, "power transducer gain error") << causes(r);
}

TEST(MonitorCore, DampingChangeIsolatesTheDamping) {
  SyntheticSet set;
  SyntheticChange c;
  c.at_s = 900.0;
  c.model = sopdt(46.3, 2.03, 0.06);
  const RunResult r = run(set, c, 1500.0);
  ASSERT_FALSE(r.alarms.empty());
  EXPECT_EQ(r.alarms.front().cause, "alternator damping change") << causes(r);
}

TEST(MonitorCore, DelayIncreaseIsTheFuelDeadTime) {
  SyntheticSet set;
  SyntheticChange c;
  c.at_s = 900.0;
  c.model = sopdt(46.3, 2.03, 0.10, 0.078 + 0.02);
  const RunResult r = run(set, c, 1500.0);
  ASSERT_FALSE(r.alarms.empty());
  EXPECT_EQ(r.alarms.front().cause, "fuel dead time or combustion lag change") << causes(r);
}

TEST(MonitorCore, LevelStepWithoutTransientIsTheTransducerOffset) {
  SyntheticSet set;
  SyntheticChange c;
  c.at_s = 900.0;
  c.level_step_kw = 70.0;  // 2 % of P0
  const RunResult r = run(set, c, 1700.0);
  ASSERT_FALSE(r.alarms.empty()) << causes(r);
  EXPECT_EQ(r.alarms.front().cause, "power transducer offset") << causes(r);
  EXPECT_EQ(r.alarms.front().fault_class, "additive");
}

// Siegmund's approximation against a Monte Carlo of the one-sided CUSUM on N(0,1) values.
TEST(SequentialTest, CusumRunLengthMatchesSiegmund) {
  const double k = 0.75, h = 3.0;
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> normal;
  double total = 0.0;
  const int runs = 4000;
  for (int i = 0; i < runs; ++i) {
    double g = 0.0;
    long n = 0;
    do {
      g = std::max(0.0, g + normal(rng) - k);
      ++n;
    } while (g <= h);
    total += static_cast<double>(n);
  }
  const double mc = total / runs;
  EXPECT_NEAR(mc / cusum_arl0(k, h), 1.0, 0.12) << "Monte Carlo " << mc;
}

TEST(SequentialTest, DesignMeetsTheRate) {
  const CusumDesign d = design_cusum(0.5, 20.48, 6, 0.75);
  EXPECT_LE(d.false_alarms_per_month, 0.5);
  EXPECT_GT(d.false_alarms_per_month, 0.45);  // the smallest h that meets it
  // A 3-sigma shift is found within a few blocks.
  EXPECT_LT(cusum_arl1(d.k, d.h, 3.0), 8.0);
}

TEST(SequentialTest, SpreadIsInflatedForCorrelationAndFewValues) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  std::vector<double> v;
  double x = 0.0;
  for (int i = 0; i < 200; ++i) {
    x = 0.6 * x + normal(rng);
    v.push_back(x);
  }
  const Spread s = learn_spread(v);
  EXPECT_GT(s.rho, 0.3);
  EXPECT_GT(s.sigma, 1.5 * s.raw_sigma);
}

std::vector<double> shaped_record(const std::function<double(double)>& f) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 3.0);
  std::vector<double> x;
  for (int k = 0; k < 6000; ++k) x.push_back(3500.0 + f((k - 2000) * 0.01) + normal(rng));
  return x;
}

TEST(EventShape, TellsASensorStepFromARecoveredLossAndALoadChange) {
  const auto step = shaped_record([](double t) { return t >= 0 ? 80.0 : 0.0; });
  EXPECT_EQ(classify_shape(step, 0.01, 1900, 2050).kind, ShapeKind::kSensorStep);
  const auto dip = shaped_record(
      [](double t) { return t >= 0 ? -300.0 * (t / 0.5) * std::exp(1.0 - t / 0.5) : 0.0; });
  EXPECT_EQ(classify_shape(dip, 0.01, 1900, 2050).kind, ShapeKind::kPowerLossRecovered);
  const auto load =
      shaped_record([](double t) { return t >= 0 ? 150.0 * (1.0 - std::exp(-t / 2.0)) : 0.0; });
  EXPECT_EQ(classify_shape(load, 0.01, 1900, 2050).kind, ShapeKind::kLevelChange);
}

TEST(TrackedParameters, DeformationsMoveOnlyTheirParameter) {
  const model::TransferFunction g = sopdt();
  const auto& table = tracked_parameters();
  for (const auto& p : table) {
    const model::TransferFunction d = p.deform(g, 0.1);
    const ModeFigures before = dominant_mode(g), after = dominant_mode(d);
    if (p.name == "gain") {
      EXPECT_NEAR(d.dc_gain() / g.dc_gain(), 1.1, 1e-9);
    }
    if (p.name == "damping") {
      EXPECT_NEAR(after.zeta / before.zeta, 1.1, 1e-6);
      EXPECT_NEAR(d.dc_gain(), g.dc_gain(), 1e-6 * g.dc_gain());
    }
    if (p.name == "frequency") {
      EXPECT_NEAR(after.fn_hz / before.fn_hz, 1.1, 1e-6);
      EXPECT_NEAR(d.dc_gain(), g.dc_gain(), 1e-6 * g.dc_gain());
    }
    if (p.name == "delay") {
      EXPECT_NEAR(d.delay_s - g.delay_s, 0.1, 1e-12);
    }
  }
}

}  // namespace
}  // namespace rig::monitor

namespace rig::monitor {
namespace {

TEST(SensorTest, TellsAGainErrorFromAnOffset) {
  // A +4 % level with the gain following it (gain error) and with the gain still (offset);
  // per-block gain standard error 2 %.
  SensorTest gain(3500.0, 6), offset(3500.0, 6);
  for (int k = 0; k < SensorTest::kMaxBlocks && !(gain.decided() && offset.decided()); ++k) {
    const double wobble = (k % 2 == 0 ? 0.004 : -0.004);
    gain.add(3500.0 * 1.04, 0.04 + wobble, 0.02);
    offset.add(3500.0 * 1.04, wobble, 0.02);
  }
  ASSERT_TRUE(gain.decided());
  ASSERT_TRUE(offset.decided());
  EXPECT_GT(gain.p_gain(), 0.95);
  EXPECT_LT(offset.p_gain(), 0.05);
}

TEST(AmplitudeTest, AmplitudeDependentGainLossIsPlay) {
  AmplitudeTest play("t", 1), dead("t", 1);
  for (int k = 0; k < AmplitudeTest::kBlocks; ++k) {
    const bool low = play.scale() < 1.0;
    // Play: twice the gain lost at half amplitude; dead time: the same fit at both levels.
    play.add(low ? -0.08 : -0.04, low ? 0.01 : 0.005);
    dead.add(-0.02, low ? 0.01 : 0.005);
  }
  ASSERT_TRUE(play.done());
  EXPECT_GT(play.z(), AmplitudeTest::kPlayZ);
  EXPECT_LT(std::abs(dead.z()), 1.0);
}

}  // namespace
}  // namespace rig::monitor
