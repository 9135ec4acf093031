// The grid's share through a recorded bus frequency (rig/diagnose/bus_frequency.hpp): a null
// record with a grid's wander answered through a droop, and an islanded set whose frequency
// is its own answer to the bias.
#include "rig/diagnose/bus_frequency.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "records.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/verdict.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::diagnose {
namespace {

constexpr std::uint64_t kSeed = 20261127;

// A first-order lag of tau_s (settled at the first sample).
Eigen::VectorXd lagged(const Eigen::VectorXd& x, double dt_s, double tau_s) {
  const double a = std::exp(-dt_s / tau_s);
  Eigen::VectorXd out(x.size());
  double v = x(0);
  for (Eigen::Index k = 0; k < x.size(); ++k) out(k) = v = a * v + (1.0 - a) * x(k);
  return out;
}

// A grid's frequency wander about 50 Hz: OU, 8 s, 4 mHz rms (seeded).
Eigen::VectorXd grid_wander_hz(Eigen::Index n, double dt_s, std::uint64_t seed) {
  const double a = std::exp(-dt_s / 8.0);
  const Eigen::VectorXd w = test::white(n, 0.004 * std::sqrt(1.0 - a * a), seed);
  Eigen::VectorXd f(n);
  double v = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) f(k) = v = a * v + w(k);
  return f;
}

struct GridRecord {
  DiagnoseInput input;
  Eigen::VectorXd share;  // the grid's share added to the null record's output
};

// The null record with the droop's answer to the wander (a lag of 0.3 s, rms 0.3 of the
// output's) added, and the frequency as recorded (0.5 mHz noise, 1 mHz steps).
GridRecord grid_record(std::uint64_t seed) {
  GridRecord g{test::null_record(seed), {}};
  DiagnoseInput& in = g.input;
  const Eigen::Index n = in.y.size();
  const Eigen::VectorXd df = grid_wander_hz(n, in.dt_s, seed + 1);
  const Eigen::VectorXd answer = -lagged(df, in.dt_s, 0.3);
  g.share = answer * (0.3 * test::rms(in.y) / test::rms(answer));
  in.y += g.share;
  Eigen::VectorXd f = (50.0 + df.array()).matrix() + test::white(n, 0.0005, seed + 2);
  in.bus_freq_hz = (f.array() / 0.001).round() * 0.001;
  return g;
}

TEST(BusFrequency, TheGridsWanderThroughTheDroopIsTakenOut) {
  const GridRecord g = grid_record(kSeed);
  SCOPED_TRACE(::testing::Message() << "seed " << kSeed);
  const DiagnoseResult with = diagnose(g.input);
  ASSERT_TRUE(with.bus_frequency.has_value());
  EXPECT_TRUE(with.bus_frequency->used) << with.bus_frequency->note;
  EXPECT_LT(with.bus_frequency->bias_coherence, thresholds::kBusFrequencyMaxBiasCoherence);
  EXPECT_NEAR(with.bus_frequency->share_rms, test::rms(g.share), 0.1 * test::rms(g.share));
  EXPECT_EQ(with.verdict, "none") << with.explanation;
  EXPECT_NE(with.explanation.find("bus frequency"), std::string::npos) << with.explanation;
  // The same record without its frequency: the wander is something the model lacks.
  DiagnoseInput without = g.input;
  without.bus_freq_hz.reset();
  const DiagnoseResult r = diagnose(without);
  EXPECT_NE(r.verdict, "none") << r.explanation;
  EXPECT_FALSE(r.bus_frequency.has_value());
  // The share of the model's residual it took: the wander's share of that residual.
  const Eigen::VectorXd residual = r.problem.y - r.baseline_yhat;
  const double expected = std::pow(test::rms(g.share) / test::rms(residual), 2);
  EXPECT_NEAR(with.bus_frequency->residual_share, expected, 0.1);
}

// A set in a 4 % droop at 50 Hz answers the grid's frequency as a bias of -50 % per Hz, on the
// governor's speed error (moving it by 0.6 of what the bias does), through the model; with
// `stop`, a one-sided rack stop behind it at 1.2 rms is hit by the bias and the wander together.
struct DroopRecord {
  DiagnoseInput input;
  double stop = 0.0;      // the rack stop, bias units about the operating point
  double rack_rms = 0.0;  // the governor's input's rms (bias and wander)
};

DroopRecord droop_record(bool stop) {
  DroopRecord d{test::null_record(kSeed)};
  DiagnoseInput& in = d.input;
  const Eigen::Index n = in.y.size();
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd noise = in.y - model::simulate(in.model, u, in.dt_s);
  constexpr double kPerHz = -50.0;  // -100 / (0.04 x 50 Hz)
  Eigen::VectorXd df = grid_wander_hz(n, in.dt_s, kSeed + 1);
  df *= 0.6 * test::rms(u) / (std::abs(kPerHz) * test::rms(df));
  Eigen::VectorXd rack = u + kPerHz * df;
  d.rack_rms = test::rms(rack);
  d.stop = 1.2 * d.rack_rms;
  if (stop) rack = rack.array().min(d.stop);
  in.y = model::simulate(in.model, rack, in.dt_s) + noise;
  const Eigen::VectorXd f = (50.0 + df.array()).matrix() + test::white(n, 0.0005, kSeed + 2);
  in.bus_freq_hz = (f.array() / 0.001).round() * 0.001;
  return d;
}

TEST(BusFrequency, TheGridsWanderReachesTheGovernorAsABiasThroughItsDroop) {
  SCOPED_TRACE(::testing::Message() << "seed " << kSeed);
  const DiagnoseResult r = diagnose(droop_record(false).input);
  ASSERT_TRUE(r.bus_frequency.has_value());
  const BusFrequencyShare& b = *r.bus_frequency;
  EXPECT_TRUE(b.referred) << b.note << " a " << b.input_per_hz << " +- " << b.input_per_hz_se;
  EXPECT_NEAR(b.droop_pct, 4.0, 0.2) << b.note;  // 5 %: the frequency's noise and steps
  EXPECT_NE(b.note.find("droop"), std::string::npos) << b.note;
  EXPECT_EQ(r.verdict, "none") << r.explanation;
}

TEST(BusFrequency, ARackStopHitByTheBiasAndTheGridsWanderIsASaturation) {
  SCOPED_TRACE(::testing::Message() << "seed " << kSeed);
  const DroopRecord d = droop_record(true);
  const DiagnoseResult r = diagnose(d.input);
  ASSERT_TRUE(r.bus_frequency.has_value());
  EXPECT_TRUE(r.bus_frequency->referred) << r.bus_frequency->note;
  EXPECT_EQ(r.verdict, "saturation") << r.explanation;
  ASSERT_NE(r.chosen(), nullptr);
  const AppliedEffect& e = r.chosen()->effects.at(0);  // a limit: its upper, its lower's size
  ASSERT_EQ(verdict_of(*r.chosen()), "saturation");
  ASSERT_GE(e.params.size(), 2u);
  EXPECT_NEAR(e.params[0], d.stop, 0.1 * d.stop) << r.explanation;
  // One-sided, as the stop is: the other limit beyond 3 rms of the governor's input (on the
  // bias alone, the wander's share of the stop is fitted as a second limit at 2.3).
  EXPECT_GT(e.params[1], 3.0 * d.rack_rms) << r.explanation;
}

TEST(BusFrequency, AnIslandedSetsFrequencyIsLeftAlone) {
  DiagnoseInput in = test::null_record(kSeed);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  // The set's own frequency: its power's answer to the bias through the inertia (1 s).
  const Eigen::VectorXd own = lagged(u, in.dt_s, 1.0);
  in.bus_freq_hz = (50.0 + (0.01 / test::rms(own)) * own.array()).matrix() +
                   test::white(in.y.size(), 0.0005, kSeed + 3);
  const DiagnoseResult r = diagnose(in);
  ASSERT_TRUE(r.bus_frequency.has_value());
  EXPECT_FALSE(r.bus_frequency->used);
  EXPECT_GT(r.bus_frequency->bias_coherence, thresholds::kBusFrequencyMaxBiasCoherence);
  EXPECT_NE(r.bus_frequency->note.find("islanded"), std::string::npos) << r.bus_frequency->note;
  DiagnoseInput plain = in;
  plain.bus_freq_hz.reset();
  EXPECT_DOUBLE_EQ(r.fit_before_pct, diagnose(plain).fit_before_pct);
}

TEST(BusFrequency, AConstantFrequencyChangesNothing) {
  DiagnoseInput in = test::null_record(kSeed);
  in.bus_freq_hz = Eigen::VectorXd::Constant(in.y.size(), 50.0);
  const DiagnoseResult r = diagnose(in);
  ASSERT_TRUE(r.bus_frequency.has_value());
  EXPECT_FALSE(r.bus_frequency->used);
  EXPECT_TRUE(r.bus_frequency->note.empty());
  EXPECT_EQ(r.explanation.find("bus frequency"), std::string::npos) << r.explanation;
}

TEST(BusFrequency, AFrequencyOfAnotherLengthIsAOneLineError) {
  DiagnoseInput in = test::null_record(kSeed);
  in.bus_freq_hz = Eigen::VectorXd::Constant(in.y.size() - 1, 50.0);
  try {
    diagnose(in);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bus frequency"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rig::diagnose
