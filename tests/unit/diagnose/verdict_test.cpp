// The verdict's evidence rules (diagnose.cpp choose, docs/diagnose.md step 4): what a fitted
// value must show before it is named, an effect present from an onset, the output's
// direction of motion and the input tests behind a drift.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "concealed.hpp"
#include "records.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/split.hpp"

namespace rig::diagnose {
namespace {

using test::null_record;
using test::rms;
using test::white;

Location located(const DiagnoseInput& in) {
  int blocks = 0;
  Eigen::Index warm = 0;
  const Problem pr = prepare_problem(in, &blocks, &warm);
  return locate(pr, model_output(pr, {}).yhat);
}

TEST(Verdict, APeakAtItsDampingBoundIsNoEvidenceOfAMode) {
  const auto credible = effect_model(Effect::kResonance).credible;
  ASSERT_NE(credible, nullptr);
  // freq_hz, zeta, peak_ratio, hf_gain
  EXPECT_FALSE(credible({Effect::kResonance, {1.3, 0.4, 0.7, 0.65}}, {}));  // broad reshaping
  EXPECT_TRUE(credible({Effect::kResonance, {1.3, 0.05, 3.0, 1.0}}, {}));   // a peak
  // A mode in series above the band shows only its flank: its damping is free.
  EXPECT_TRUE(credible({Effect::kResonance, {4.5, 0.4, 0.05, 0.0}}, {}));
}

TEST(Verdict, ALimiterWhoseRecoveryStoppedAtItsBoundIsNoEvidenceOfALimit) {
  DataScales s;  // a 120 s record at 100 Hz: recovery_s at most 12 s
  s.dt_s = 0.01;
  s.duration_s = 120.0;
  const auto sat = effect_model(Effect::kSaturation).credible;
  const auto rate = effect_model(Effect::kRateLimit).credible;
  ASSERT_NE(sat, nullptr);
  ASSERT_NE(rate, nullptr);
  EXPECT_FALSE(sat({Effect::kSaturation, {0.4, 0.7, 12.0}}, s));
  EXPECT_TRUE(sat({Effect::kSaturation, {0.4, 0.7, 3.0}}, s));   // a governor's loop
  EXPECT_TRUE(sat({Effect::kSaturation, {0.4, 0.7, 0.01}}, s));  // a plain limit
  EXPECT_FALSE(rate({Effect::kRateLimit, {5.0, 11.9}}, s));
  EXPECT_TRUE(rate({Effect::kRateLimit, {5.0, 2.0}}, s));
}

TEST(Verdict, ARateLimitFromHalfWayIsFoundInTheLoopFromItsOnset) {
  DiagnoseInput in = null_record(45);
  const double lag_s = 0.15;
  const Eigen::Index onset = in.u.size() / 2;
  double limit = 0.0;
  const Eigen::VectorXd v = test::in_loop_rate_limited(in, lag_s, &limit, onset);
  const Eigen::VectorXd z = model::simulate(rest_after_front(in.model, lag_s), v, in.dt_s);
  in.y = z + white(z.size(), 0.15 * rms(z), 11);
  const DiagnoseResult r = diagnose(in);
  ASSERT_EQ(r.verdict, "rate_limit") << r.explanation;
  const HypothesisFit& h = *r.chosen();
  EXPECT_EQ(h.effects.front().place, Place::kInLoop) << r.explanation;
  EXPECT_NEAR(static_cast<double>(h.active_from), static_cast<double>(onset), 0.1 * onset);
  EXPECT_NEAR(h.effects.front().params[0], limit, 0.2 * limit) << r.explanation;
}

TEST(Verdict, AForceAgainstTheOutputsMotionShowsInTheOutputDirectionTest) {
  DiagnoseInput in = null_record(46);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd z0 = model::simulate(in.model, u, in.dt_s);
  Eigen::VectorXd dir = Eigen::VectorXd::Zero(u.size());
  for (Eigen::Index i = 1; i < u.size(); ++i) dir(i) = z0(i) > z0(i - 1) ? 1.0 : -1.0;
  // A dry-friction-like force on the output's motion, fed back to the input.
  const Eigen::VectorXd z = model::simulate(in.model, u - 0.3 * rms(u) * dir, in.dt_s);
  in.y = z + white(z.size(), 0.1 * rms(z), 12);
  EXPECT_GT(std::abs(located(in).amp.output_direction_z), 5.0);
  // On null records the statistic is about standard normal: beyond the evidence bound of 3
  // in 0.3 % of them.
  int beyond = 0;
  for (std::uint64_t seed = 46; seed < 60; ++seed) {
    DiagnoseInput null = null_record(seed);
    const Eigen::VectorXd u0 = null.u.array() - null.u.mean();
    const Eigen::VectorXd zn = model::simulate(null.model, u0, null.dt_s);
    null.y = zn + white(zn.size(), 0.1 * rms(zn), seed + 100);
    beyond += std::abs(located(null).amp.output_direction_z) >= 3.0;
  }
  EXPECT_LE(beyond, 1);
}

TEST(Verdict, AnInputEffectBehindALargeDriftIsStillLocated) {
  DiagnoseInput in = null_record(47);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd z = model::simulate(in.model, deadband(u, 0.5 * rms(u)), in.dt_s);
  // A wander of the output (integrated noise smoothed over 5 s) twice the response's rms.
  Eigen::VectorXd drift = white(z.size(), 1.0, 13);
  for (Eigen::Index i = 1; i < drift.size(); ++i) drift(i) += drift(i - 1);
  drift = smooth_zero_phase(drift, 5.0, in.dt_s);
  drift *= 2.0 * rms(z) / rms(drift);
  in.y = z + drift + white(z.size(), 0.05 * rms(z), 14);
  const Location loc = located(in);
  EXPECT_TRUE(loc.dist.drift);
  EXPECT_TRUE(loc.input_mismatch);
  const DiagnoseResult r = diagnose(in);
  EXPECT_EQ(r.verdict, "deadband") << r.explanation;
}

}  // namespace
}  // namespace rig::diagnose
