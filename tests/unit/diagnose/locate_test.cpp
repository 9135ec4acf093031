#include "rig/diagnose/locate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "concealed.hpp"
#include "records.hpp"
#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/split.hpp"

namespace rig::diagnose {
namespace {

struct Located {
  Problem pr;
  Location loc;
};

Located locate_case(std::optional<Effect> e, Concealment c, std::uint64_t seed) {
  ConcealedSpec spec;
  spec.effect = e, spec.concealment = c, spec.seed = seed, spec.duration_s = 200.0;
  const ConcealedRecording rec = make_concealed(spec);
  int blocks = 0;
  Eigen::Index warm = 0;
  Located out{prepare_problem(rec.input, &blocks, &warm), {}};
  out.loc = locate(out.pr, model_output(out.pr, {}).yhat);
  return out;
}

TEST(Locate, NullCaseFindsNothing) {
  for (std::uint64_t seed : {11u, 12u, 13u}) {
    const Located l = locate_case(std::nullopt, Concealment::kNoise, seed);
    EXPECT_FALSE(l.loc.input_mismatch) << "seed " << seed;
    EXPECT_FALSE(l.loc.disturbance) << "seed " << seed;
    EXPECT_TRUE(l.loc.windows.empty()) << "seed " << seed;
  }
}

TEST(Locate, DeadTimeShowsAsABandAndAPhaseSlope) {
  const Located l = locate_case(Effect::kDeadTime, Concealment::kNoise, 21);
  ASSERT_TRUE(l.loc.freq.band_hz);
  EXPECT_FALSE(l.loc.tests.independent);
  EXPECT_NEAR(l.loc.freq.delay_from_phase_s, 0.04, 0.008);  // truth 40 ms
  EXPECT_FALSE(l.loc.amp.amplitude_dependent);
}

TEST(Locate, DeadbandIsAmplitudeDependentWithLowGainAtSmallLevels) {
  const Located l = locate_case(Effect::kDeadband, Concealment::kNoise, 22);
  EXPECT_TRUE(l.loc.amp.amplitude_dependent);
  EXPECT_LT(l.loc.amp.by_level.front().gain, l.loc.amp.by_level.back().gain);
}

TEST(Locate, PartialEffectIsLocatedInTime) {
  // The effect starts at 40 % of the record (80 s of 200 s).
  const Located l = locate_case(Effect::kExtraLag, Concealment::kPartial, 23);
  ASSERT_FALSE(l.loc.windows.empty());
  EXPECT_NEAR(l.loc.windows.front().from_s, 80.0, 10.0);
  EXPECT_GT(l.loc.windows.back().to_s, 180.0);
}

TEST(Locate, PeriodicDisturbanceIsALineUncorrelatedWithTheInput) {
  const Located l = locate_case(Effect::kPeriodicDisturbance, Concealment::kNoise, 24);
  EXPECT_TRUE(l.loc.dist.periodic);
  EXPECT_NEAR(l.loc.dist.line_freq_hz, 0.73, 0.005);
}

// A lag that appears half-way: the residual is correlated with the input in the second half
// only; on null records neither half fires (each half's test holds half of the 1 %).
TEST(Locate, AnEffectInTheSecondHalfIsSeenInThatHalf) {
  DiagnoseInput in = test::null_record(71);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  model::TransferFunction lagged = in.model;
  lagged.den = poly_multiply(lagged.den, Eigen::Vector2d(0.03, 1.0));
  Eigen::VectorXd z = model::simulate(in.model, u, in.dt_s);
  const Eigen::Index mid = z.size() / 2;
  z.tail(z.size() - mid) = model::simulate(lagged, u, in.dt_s).tail(z.size() - mid);
  in.y = z + test::white(z.size(), 0.15 * test::rms(z), 15);
  int blocks = 0;
  Eigen::Index warm = 0;
  const Problem pr = prepare_problem(in, &blocks, &warm);
  const Location loc = locate(pr, model_output(pr, {}).yhat);
  EXPECT_TRUE(loc.halves[0].independent);
  EXPECT_FALSE(loc.halves[1].independent);
  EXPECT_TRUE(loc.input_mismatch);
  int fired = 0;
  for (std::uint64_t seed = 71; seed < 85; ++seed) {
    DiagnoseInput null = test::null_record(seed);
    const Eigen::VectorXd u0 = null.u.array() - null.u.mean();
    const Eigen::VectorXd zn = model::simulate(null.model, u0, null.dt_s);
    null.y = zn + test::white(zn.size(), 0.15 * test::rms(zn), seed + 200);
    const Problem pn = prepare_problem(null, &blocks, &warm);
    fired += locate(pn, model_output(pn, {}).yhat).half_dependent >= 0;
  }
  EXPECT_LE(fired, 1);
}

// A transducer gain that drops to 0.92 half-way on a power reading: the level steps by
// (g - 1) x level, which is taken out, and the gain is fitted from the step on (over the
// whole record the half without it dilutes it below its parameter's worth).
TEST(Locate, AGainChangeWithTheLevelInItIsFittedFromTheLevelStep) {
  DiagnoseInput in = test::null_record(71);
  const Eigen::VectorXd z = model::simulate(in.model, in.u, in.dt_s);
  const double level = 200.0 * test::rms(z), gain = 0.92;
  const Eigen::Index n = z.size(), half = n / 2;
  in.y = z.array() + level;
  in.y.tail(n - half) *= gain;
  in.y += test::white(n, 0.1 * test::rms(z), 23);
  const DiagnoseResult r = diagnose(in);
  ASSERT_TRUE(r.level_shift_time_s.has_value()) << r.explanation;
  EXPECT_NEAR(*r.level_shift_time_s, static_cast<double>(half) * in.dt_s, 1.0);
  ASSERT_EQ(r.verdict, "gain_change") << r.explanation;
  const HypothesisFit& h = *r.chosen();
  EXPECT_NEAR(h.effects.front().params[0], gain, 0.03) << r.explanation;
  EXPECT_NEAR(static_cast<double>(h.active_from), static_cast<double>(half), 1.0 / in.dt_s);
}

// The step-gain test tells the two readings of a level step apart: a transducer gain that
// drops to 0.8 scales the response with the level (it fires, and agrees with the level's
// ratio); an operating-point step of the same size leaves the response as it was.
TEST(Locate, TheResponseTellsAGainChangeFromAnOperatingPointStep) {
  for (const bool gain_change : {true, false}) {
    DiagnoseInput in = test::null_record(72);
    const Eigen::VectorXd z = model::simulate(in.model, in.u, in.dt_s);
    const double level = 100.0 * test::rms(z), ratio = 0.8;
    const Eigen::Index n = z.size(), half = n / 2;
    in.y = z.array() + level;
    if (gain_change)
      in.y.tail(n - half) *= ratio;
    else
      in.y.tail(n - half).array() -= (1.0 - ratio) * level;
    in.y += test::white(n, 0.3 * test::rms(z), 24);
    // The level before the step (the input's operating point gives z a mean of its own).
    const double before = in.y.head(half).mean();
    const DiagnoseResult r = diagnose(in);
    ASSERT_TRUE(r.level_shift_time_s.has_value()) << r.explanation;
    const StepGain& g = r.location.step_gain;
    ASSERT_TRUE(g.tested) << r.explanation;
    EXPECT_NEAR(g.level_ratio, gain_change ? ratio : 1.0 - (1.0 - ratio) * level / before, 0.01)
        << r.explanation;
    EXPECT_NEAR(g.change, gain_change ? ratio - 1.0 : 0.0, 3.0 * g.sd) << r.explanation;
    EXPECT_LT(g.sd, 0.03) << "too noisy to tell the two apart";
    EXPECT_EQ(g.fires, gain_change) << r.explanation;
    EXPECT_EQ(r.verdict, gain_change ? "gain_change" : "none") << r.explanation;
    const char* words = gain_change ? "not the operating point" : "the operating point changed";
    EXPECT_NE(r.explanation.find(words), std::string::npos) << r.explanation;
  }
}

// A null record with a level step taken out half-way, and the baseline's output: the
// step-gain test's setting.
struct StepRecord {
  StepRecord() {
    int blocks = 0;
    Eigen::Index warm = 0;
    pr = prepare_problem(test::null_record(73), &blocks, &warm);
    yh = model_output(pr, {}).yhat;
    half = yh.size() / 2;
    pr.level_step_removed_at = half;
  }
  Problem pr;
  Eigen::VectorXd yh;
  Eigen::Index half = 0;
};

// The step-gain test weighs the two readings of a level step (thresholds.hpp,
// kStepGainLikelihoodRatio), on 300 seeded noise draws each: a gain change 3.5 sd of its own
// test from none (|z| mostly under the old bound of 5) fires in most draws, and an
// operating-point step leaves the gain as it was and fires in few, also at the step size
// (2.15 sd) where that is likeliest.
TEST(Locate, TheStepGainTestWeighsTheLevelsReadingAgainstNoChange) {
  StepRecord rec;
  Problem& pr = rec.pr;
  const Eigen::VectorXd& yh = rec.yh;
  const Eigen::Index n = yh.size(), half = rec.half;
  const double noise = 0.3 * test::rms(yh);
  // The test's own sd at this noise (it does not depend on the level's ratio).
  const double sd = locate_step_gain(pr, test::white(n, noise, 1), yh, 1.0).sd;
  ASSERT_GT(sd, 0.0);
  constexpr int kDraws = 300;
  const auto fired = [&](double d_gain, double d_level) {
    int count = 0;
    for (int i = 0; i < kDraws; ++i) {
      Eigen::VectorXd r = test::white(n, noise, 1000 + static_cast<std::uint64_t>(i));
      r.tail(n - half) -= d_gain * sd * yh.tail(n - half);  // the gain after, minus 1
      count += locate_step_gain(pr, r, yh, 1.0 - d_level * sd).fires ? 1 : 0;
    }
    std::printf("gain %.2f sd, level %.2f sd (sd %.4f): fired in %d of %d draws\n", d_gain, d_level,
                sd, count, kDraws);
    return count;
  };
  // A gain change of 3.5 sd: fires when z > 2.41 (1.75 + ln 10 / 3.5), in 86 % of draws;
  // |z| > 5 alone would fire in 7 %.
  EXPECT_GE(fired(3.5, 3.5), kDraws * 70 / 100);
  // Operating-point steps that leave the gain: at most 1.6 % of draws (binomial, 300 draws:
  // the mean 4.8, 12 is beyond its 99.9 % point).
  EXPECT_LE(fired(0.0, 2.15), 12);
  EXPECT_LE(fired(0.0, 3.5), 12);
  // A gain change against the level's ratio (an operating point whose gain moved the other
  // way) never agrees with it.
  EXPECT_EQ(fired(-3.5, 3.5), 0);
}

// The same on coloured noise (white through a one-pole low-pass at 0.9 per sample, as a
// transducer's lag or the grid's wander colour the residual): with the test's generalised
// least squares (an AR whitener of its first fit's residual) operating-point steps still fire
// in few draws and a gain change of 3.5 of its sd in most.
TEST(Locate, TheStepGainTestKeepsItsSizeOnColouredNoise) {
  StepRecord rec;
  Problem& pr = rec.pr;
  const Eigen::VectorXd& yh = rec.yh;
  const Eigen::Index n = yh.size(), half = rec.half;
  const auto coloured = [&](std::uint64_t seed) {
    Eigen::VectorXd w = test::white(n, 0.3 * test::rms(yh), seed);
    for (Eigen::Index k = 1; k < n; ++k) w(k) += 0.9 * w(k - 1);
    return w;
  };
  const double sd = locate_step_gain(pr, coloured(1), yh, 1.0).sd;
  ASSERT_GT(sd, 0.0);
  constexpr int kDraws = 300;
  const auto fired = [&](double d_gain, double d_level) {
    int count = 0;
    for (int i = 0; i < kDraws; ++i) {
      Eigen::VectorXd r = coloured(2000 + static_cast<std::uint64_t>(i));
      r.tail(n - half) -= d_gain * sd * yh.tail(n - half);
      count += locate_step_gain(pr, r, yh, 1.0 - d_level * sd).fires ? 1 : 0;
    }
    std::printf("coloured: gain %.2f sd, level %.2f sd (sd %.4f): fired in %d of %d draws\n",
                d_gain, d_level, sd, count, kDraws);
    return count;
  };
  EXPECT_GE(fired(3.5, 3.5), kDraws * 70 / 100);
  EXPECT_LE(fired(0.0, 2.15), 12);
  EXPECT_LE(fired(0.0, 3.5), 12);
}

// The coupling test (locate_coupling.cpp, thresholds.hpp kCouplingLikelihoodRatio) on 60
// seeded draws each, beside coloured noise (white through a one-pole low-pass at 0.9 per
// sample): a slow wander three times a coupling's residual (three swings of 40-100 s, random
// phases: a drift) fires in none, and the residual an AC coupling of RC 8 s leaves
// (-LP_RC(yhat)) in most, its RC read within a factor 2.
TEST(Locate, TheCouplingTestTellsACouplingFromAWander) {
  StepRecord rec;
  const Problem& pr = rec.pr;
  const Eigen::VectorXd& yh = rec.yh;
  const Eigen::Index n = yh.size();
  const Eigen::VectorXd dev = yh.array() - yh.mean();
  Eigen::VectorXd coupled(n);  // -LP_RC(yhat): what the coupling takes out of the output
  const double rc_s = 8.0, a = pr.dt_s / (rc_s + pr.dt_s);
  double state = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) coupled(k) = -(state += a * (dev(k) - state));
  const double size = test::rms(coupled);
  // White noise at twice the coupling's rms, coloured to about 4.6 times it; the wander at
  // three times it.
  constexpr double kNoiseOfCoupling = 2.0, kWanderOfCoupling = 3.0;
  const auto coloured = [&](std::uint64_t seed) {
    Eigen::VectorXd w = test::white(n, kNoiseOfCoupling * size, seed);
    for (Eigen::Index k = 1; k < n; ++k) w(k) += 0.9 * w(k - 1);
    return w;
  };
  const auto wander = [&](std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi), period(40.0, 100.0);
    Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < 3; ++i) {
      const double p = period(rng), f = phase(rng);
      for (Eigen::Index k = 0; k < n; ++k)
        w(k) += std::sin(2.0 * std::numbers::pi * static_cast<double>(k) * pr.dt_s / p + f);
    }
    return Eigen::VectorXd(w * (kWanderOfCoupling * size / test::rms(w)));
  };
  constexpr int kDraws = 60;
  int wander_fired = 0, coupling_fired = 0, rc_read = 0;
  for (int i = 0; i < kDraws; ++i) {
    const auto seed = 3000 + static_cast<std::uint64_t>(i);
    wander_fired += locate_coupling(pr, coloured(seed) + wander(seed), yh).fires ? 1 : 0;
    const CouplingTest c = locate_coupling(pr, coloured(seed) + coupled, yh);
    coupling_fired += c.fires ? 1 : 0;
    rc_read += c.fires && std::abs(std::log(c.rc_s / rc_s)) <= std::log(2.0) ? 1 : 0;
  }
  std::printf(
      "coupling test: a wander fired in %d of %d draws, a coupling of RC %.0f s in %d "
      "(RC within a factor 2 in %d); coupling rms %.4g, yhat rms %.4g\n",
      wander_fired, kDraws, rc_s, coupling_fired, rc_read, size, test::rms(yh));
  EXPECT_EQ(wander_fired, 0);
  EXPECT_GE(coupling_fired, kDraws * 90 / 100);
  EXPECT_GE(rc_read, kDraws * 90 / 100);
}

// The value of y below which a fraction q of its samples lie.
double quantile(const Eigen::VectorXd& y, double q) {
  std::vector<double> v(y.data(), y.data() + y.size());
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

// A sensor at the end of its range: the nominal record clipped at its 97th percentile. The
// clip is found, every model (the baseline too) is compared through it, and the model that
// made the record explains it: `none`, with the clip said.
TEST(Locate, AClippedOutputIsFoundAndTheModelIsComparedThroughIt) {
  DiagnoseInput in = test::null_record(31);
  const double level = quantile(in.y, 0.97);
  in.y = in.y.cwiseMin(level);
  const DiagnoseResult r = diagnose(in);
  EXPECT_EQ(r.problem.output_clip.side, +1);
  EXPECT_EQ(r.problem.output_clip.level, level);
  EXPECT_NEAR(static_cast<double>(r.problem.output_clip.samples), 0.03 * in.y.size(), 2.0);
  EXPECT_FALSE(r.location.input_mismatch);
  EXPECT_LE(r.baseline_yhat.maxCoeff(), level - r.problem.y_level + 1e-9);
  EXPECT_EQ(r.verdict, "none") << r.explanation;
  EXPECT_NE(r.explanation.find("clipped"), std::string::npos) << r.explanation;
}

// A quantised output repeats values, least towards its extremes: not a clip. Clipped at the
// bottom (a quantised transducer's floor), it is one.
TEST(Locate, AQuantisedOutputIsNotClippedButOneAtItsFloorIs) {
  const DiagnoseInput in = test::null_record(32);
  EXPECT_EQ(find_output_clip(in.y).side, 0);
  for (const double step_rms : {0.02, 0.25}) {
    const double step = step_rms * test::rms(in.y);
    const Eigen::VectorXd q = (in.y / step).array().round() * step;
    EXPECT_EQ(find_output_clip(q).side, 0) << step_rms;
  }
  const double step = 0.02 * test::rms(in.y);
  const Eigen::VectorXd q = (in.y / step).array().round() * step;
  const double floor = quantile(q, 0.02);
  const OutputClip c = find_output_clip(q.cwiseMax(floor));
  EXPECT_EQ(c.side, -1);
  EXPECT_EQ(c.level, floor);
}

// The sign test over rows: an answer to rises larger than to falls in the second half only
// shows there and not in the first half (operating_point.cpp repeats it on each side of a
// grid event).
TEST(Locate, TheSignTestOverRowsSeesAnAsymmetryOnlyWhereItIs) {
  const DiagnoseInput in = test::null_record(41);
  int blocks = 0;
  Eigen::Index warm = 0;
  Problem pr = prepare_problem(in, &blocks, &warm);
  const Eigen::Index n = pr.y.size(), half = n / 2;
  const Eigen::VectorXd up = model::simulate(pr.tf, pr.u.cwiseMax(0.0), pr.dt_s);
  pr.y.tail(n - half) += 0.15 * up.tail(n - half);
  const Eigen::VectorXd yhat = model_output(pr, {}).yhat;
  const Eigen::VectorXd r = pr.y - yhat;
  const double first = sign_z(pr, r, yhat, 0, half), second = sign_z(pr, r, yhat, half, -1);
  EXPECT_LT(std::abs(first), 3.0) << first;
  EXPECT_GT(second, 5.0) << second;
  // The whole record's test sees it too, diluted.
  const double whole = sign_z(pr, r, yhat, 0, -1);
  EXPECT_GT(whole, 3.0) << whole;
  EXPECT_LT(whole, second * 1.2) << whole;
}

// The level test over rows: a gain that only the larger half of |u| sees (the response
// doubled there), from half-way, is found on the second half and not on the first; over the whole
// record it is the test of locate_amplitude.
TEST(Locate, TheLevelTestOverRowsSeesALevelDependentGainOnlyWhereItIs) {
  const DiagnoseInput in = test::null_record(43);
  int blocks = 0;
  Eigen::Index warm = 0;
  Problem pr = prepare_problem(in, &blocks, &warm);
  const Eigen::Index n = pr.y.size(), half = n / 2;
  std::vector<double> mags(pr.u.data(), pr.u.data() + n);
  for (double& m : mags) m = std::abs(m);
  std::nth_element(mags.begin(), mags.begin() + n / 2, mags.end());
  const double median = mags[static_cast<std::size_t>(n / 2)];
  const Eigen::VectorXd large =
      pr.u.unaryExpr([median](double v) { return std::abs(v) > median ? v : 0.0; });
  const Eigen::VectorXd extra = model::simulate(pr.tf, large, pr.dt_s);
  pr.y.tail(n - half) += extra.tail(n - half);
  const Eigen::VectorXd yhat = model_output(pr, {}).yhat;
  const Eigen::VectorXd r = pr.y - yhat;
  const LevelTest first = level_test(pr, r, yhat, 0, half),
                  second = level_test(pr, r, yhat, half, -1);
  EXPECT_FALSE(first.fires()) << first.chi2;
  EXPECT_LT(first.chi2, 13.28) << "chi^2(4) at 1 %";
  EXPECT_TRUE(second.fires()) << second.chi2;
  ASSERT_EQ(second.by_level.size(), 5u);
  EXPECT_GT(second.by_level.back().gain, second.by_level.front().gain + 0.1);
  // The whole record's is the location's, bin for bin.
  const LevelTest whole = level_test(pr, r, yhat, 0, -1);
  const AmplitudeLocation amp = locate_amplitude(pr, r, yhat);
  EXPECT_EQ(whole.chi2, amp.level_chi2);
  EXPECT_EQ(whole.fires(), amp.amplitude_dependent);
  ASSERT_EQ(whole.by_level.size(), amp.by_level.size());
  for (std::size_t b = 0; b < amp.by_level.size(); ++b) {
    EXPECT_EQ(whole.by_level[b].gain, amp.by_level[b].gain);
    EXPECT_EQ(whole.by_level[b].gain_std, amp.by_level[b].gain_std);
    EXPECT_EQ(whole.by_level[b].level, amp.by_level[b].level);
  }
}

}  // namespace
}  // namespace rig::diagnose
