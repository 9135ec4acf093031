// Where an input-side nonlinearity sits (placement.hpp) and the sampling convention as a
// nuisance (timing.hpp), on records made from the nominal genset model.
#include "rig/diagnose/placement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <span>

#include "concealed.hpp"
#include "records.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {
namespace {

using test::null_record;
using test::rms;
using test::two_level;
using test::white;

TEST(Placement, RateLimitBehindTheGovernorsLagIsFoundInTheLoop) {
  DiagnoseInput in = null_record(41);
  const double lag_s = 0.15;
  double limit = 0.0;  // bias-% equivalent per second
  const Eigen::VectorXd v = test::in_loop_rate_limited(in, lag_s, &limit);
  const Eigen::VectorXd z = model::simulate(rest_after_front(in.model, lag_s), v, in.dt_s);
  in.y = z + white(z.size(), 0.15 * rms(z), 7);
  const DiagnoseResult r = diagnose(in);
  ASSERT_EQ(r.verdict, "rate_limit") << r.explanation;
  const AppliedEffect& e = r.chosen()->effects.front();
  EXPECT_EQ(e.place, Place::kInLoop) << r.explanation;
  EXPECT_NEAR(e.params[0], limit, 0.2 * limit) << r.explanation;
  EXPECT_NE(r.explanation.find("inside the governor's loop"), std::string::npos);
}

TEST(Placement, ADeadbandOnTheBiasIsAtTheInputAndTriedAtEachPlace) {
  DiagnoseInput in = null_record(42);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd z = model::simulate(in.model, deadband(u, 0.4 * rms(u)), in.dt_s);
  in.y = z + white(z.size(), 0.1 * rms(z), 8);
  const DiagnoseResult r = diagnose(in);
  ASSERT_EQ(r.verdict, "deadband") << r.explanation;
  EXPECT_EQ(r.chosen()->effects.front().place, Place::kInput) << r.explanation;
  int places[16] = {};  // by the Place's value
  for (const auto& h : r.hypotheses)
    if (h.effects.size() == 1 && h.effects[0].effect == Effect::kDeadband)
      ++places[static_cast<int>(h.effects[0].place)];
  EXPECT_EQ(places[static_cast<int>(Place::kInput)], 1);
  EXPECT_EQ(places[static_cast<int>(Place::kInLoop)], 1);
  EXPECT_EQ(places[static_cast<int>(Place::kOutput)], 1);
  EXPECT_EQ(places[static_cast<int>(Place::kFeedback)], 0);  // not tried in the feedback
  EXPECT_EQ(places[static_cast<int>(Place::kError)], 1);     // memoryless: on the error
  EXPECT_EQ(places[static_cast<int>(Place::kPiLoop)], 1);    // stepped: after the PI
  // ... and both with the loop's feedback fitted; a linear effect's place only.
  EXPECT_EQ(places[static_cast<int>(Place::kGovernorError)], 1);
  EXPECT_EQ(places[static_cast<int>(Place::kGovernorPi)], 1);
  EXPECT_EQ(places[static_cast<int>(Place::kGovernorLoop)], 0);
}

// A limit is also tried on the governor's error (with a mostly proportional governor, a
// droop governor's, a limit of its output is one of its error: droopsim's smoke limiter,
// named `static_nonlinearity` there before): a plain clamp, the loop restoring the position.
TEST(Placement, ALimitOnTheGovernorsErrorIsAPlainClamp) {
  const auto on_error = effect_model(Effect::kSaturation).apply_on_error;
  ASSERT_NE(on_error, nullptr);
  const Params p{1.2, 3.0, 2.0};  // upper, lower magnitude, recovery_s (no part there)
  const double e[] = {5.0, -7.0, 0.4};
  EXPECT_DOUBLE_EQ(on_error(p, std::span<const double>(e, 1), 1.0, 0.01), 1.2);
  EXPECT_DOUBLE_EQ(on_error(p, std::span<const double>(e, 2), 1.0, 0.01), -3.0);
  EXPECT_DOUBLE_EQ(on_error(p, std::span<const double>(e, 3), 1.0, 0.01), 0.4);
  // There recovery_s is neither a parameter of the hypothesis nor reported; at the input it
  // is both.
  HypothesisFit h;
  h.effects = {AppliedEffect{Effect::kSaturation, p, Place::kError, {}}};
  EXPECT_EQ(acting_params(h.effects[0]), 2u);
  EXPECT_EQ(h.parameter_count(), 2);
  h.effects[0].place = Place::kInput;
  EXPECT_EQ(acting_params(h.effects[0]), 3u);
  EXPECT_EQ(h.parameter_count(), 3);
}

// A place parameter stopped at its bound is the search's stand-in for another shape: an
// integral time at 20 s (no integrator: the error's form) or 20 ms (a pure integral), an
// output lag at 0.5 s; inside them the place can be a verdict's.
TEST(Placement, APiLoopAtItsBoundsIsNoPlaceForAVerdict) {
  const auto at = [](double ti_s, double tf_s) {
    return AppliedEffect{Effect::kBacklash, {0.1}, Place::kPiLoop, {ti_s, tf_s}};
  };
  EXPECT_TRUE(place_credible(at(0.25, 0.05)));
  EXPECT_TRUE(place_credible(at(0.25, thresholds::kPiFilterMinS)));  // no filter is a place
  EXPECT_FALSE(place_credible(at(thresholds::kPiIntegralMaxS, 0.05)));
  EXPECT_FALSE(place_credible(at(thresholds::kPiIntegralMinS, 0.05)));
  EXPECT_FALSE(place_credible(at(0.25, thresholds::kPiFilterMaxS)));
}

TEST(Placement, OnATwoLevelInputNothingIsFittedOnTheBiasItself) {
  DiagnoseInput in = null_record(47);
  in.u = two_level(in.u.size(), 47);
  model::TransferFunction plant = in.model;  // a 60 ms transducer lag the model lacks
  plant.den = poly_multiply(plant.den, Eigen::Vector2d(0.06, 1.0));
  const Eigen::VectorXd z = model::simulate(plant, in.u, in.dt_s);
  in.y = z + white(z.size(), 0.1 * rms(z), 14);
  const DiagnoseResult r = diagnose(in);
  EXPECT_TRUE(r.location.amp.two_level_input);
  // sign(du/dt) is linear in du/dt here: no claim of a play from it.
  EXPECT_EQ(r.explanation.find("reversal of the input's direction"), std::string::npos);
  for (const auto& h : r.hypotheses)
    for (const auto& e : h.effects)
      EXPECT_FALSE(kind_of(e.effect) == EffectKind::kInputNonlinearity && e.place == Place::kInput)
          << to_string(e.effect);
  ASSERT_TRUE(r.verdict == "extra_lag" || r.verdict == "sensor_lag") << r.explanation;
  EXPECT_NE(r.explanation.find("two levels"), std::string::npos);
  // A Gaussian record is not two-level.
  EXPECT_FALSE(two_level_input(null_record(47).u));
}

TEST(Timing, HalfASampleOfTimingIsANullNotADeadTime) {
  for (const double shift : {0.5, -0.45}) {
    DiagnoseInput in = null_record(43);
    const Eigen::VectorXd u = in.u.array() - in.u.mean();
    model::TransferFunction plant = in.model;
    plant.delay_s += shift * in.dt_s;
    const Eigen::VectorXd z = model::simulate(plant, u, in.dt_s);
    in.y = z + white(z.size(), 0.02 * rms(z), 9);  // little noise: half a sample shows
    const DiagnoseResult r = diagnose(in);
    EXPECT_EQ(r.verdict, "none") << shift << ": " << r.explanation;
    EXPECT_NEAR(r.timing_nuisance_s, shift * in.dt_s, 0.1 * in.dt_s) << shift;
  }
}

TEST(Timing, TwoSamplesOfDelayAreStillADeadTime) {
  DiagnoseInput in = null_record(44);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  model::TransferFunction plant = in.model;
  plant.delay_s += 2.0 * in.dt_s;
  const Eigen::VectorXd z = model::simulate(plant, u, in.dt_s);
  in.y = z + white(z.size(), 0.05 * rms(z), 10);
  const DiagnoseResult r = diagnose(in);
  ASSERT_EQ(r.verdict, "dead_time") << r.explanation;
  EXPECT_NEAR(r.chosen()->effects.front().params[0], 2.0 * in.dt_s, 0.3 * in.dt_s);
  EXPECT_EQ(r.timing_nuisance_s, 0.0);
}

}  // namespace
}  // namespace rig::diagnose
