// The pairs the hypothesis search forms (pairs.hpp) and the fits on the worker threads
// (screen.hpp): a pair is formed only where both effects can sit, and a fit that cannot be
// made is an error the caller sees, not the end of the process.
#include "rig/diagnose/pairs.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "records.hpp"
#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/screen.hpp"
#include "rig/diagnose/split.hpp"

namespace rig::diagnose {
namespace {

HypothesisFit fit_of(std::vector<AppliedEffect> effects, double score) {
  HypothesisFit h;
  h.effects = std::move(effects);
  h.score = score;
  return h;
}

// A hysteresis loop's pair is compared with its play's (verdict.cpp prefer_simpler). The
// play's best single sat after the governor's PI, which cannot share a model with an effect
// on the loop's error: the pair takes the play's best place that can (the real exchanger
// record ended the process when the first was fitted).
TEST(Pairs, ASimplerPairIsFormedOnlyWhereBothEffectsCanSit) {
  const AppliedEffect play_after_pi{Effect::kBacklash, {0.2}, Place::kPiLoop, {0.5, 0.05}};
  const AppliedEffect play_at_input{Effect::kBacklash, {0.2}, Place::kInput, {}};
  const AppliedEffect loop{Effect::kHysteresis, {0.3, 0.5, 1.0, 0.5}, Place::kInput, {}};
  const AppliedEffect map_on_error{Effect::kStaticNonlinearity, {0.1, 0.0, 0.2}, Place::kError, {}};
  ASSERT_FALSE(pairable(play_after_pi, map_on_error));
  ASSERT_TRUE(pairable(play_at_input, map_on_error));
  const std::vector<HypothesisFit> singles{fit_of({play_after_pi}, 10.0),
                                           fit_of({play_at_input}, 8.0)};
  const HypothesisFit pair = fit_of({loop, map_on_error}, 12.0);
  const std::vector<Candidate> formed = simpler_pairs(singles, {&pair});
  ASSERT_EQ(formed.size(), 1u);
  const auto& start = formed.front().front();
  ASSERT_EQ(start.size(), 2u);
  EXPECT_EQ(start[0].effect, Effect::kBacklash);
  EXPECT_EQ(start[0].place, Place::kInput);
  EXPECT_EQ(start[1].effect, Effect::kStaticNonlinearity);
}

// A pair whose lag inside the governor's loop stopped at its feedback's bound, which no
// verdict names, is refitted with the lag at its best credible single place beside the same
// damping change, in the pair's order (gensim seed 7 g075); a pair already fitted, or one
// whose places are credible, is not formed again.
TEST(Pairs, APairAtABoundIsRefittedWithThatEffectAtItsCrediblePlace) {
  const AppliedEffect lag_at_bound{
      Effect::kExtraLag, {0.05}, Place::kGovernorLoop, {2.0, 0.5, 0.5}};
  const AppliedEffect lag_in_loop{Effect::kExtraLag, {0.1}, Place::kGovernorLoop, {1.7, 0.0, 0.1}};
  const AppliedEffect lag_at_input{Effect::kExtraLag, {0.15}, Place::kInput, {}};
  const AppliedEffect damping{Effect::kLoadDamping, {0.4}, Place::kInput, {}};
  ASSERT_FALSE(place_credible(lag_at_bound));
  ASSERT_TRUE(place_credible(lag_in_loop));
  const std::vector<HypothesisFit> singles{fit_of({lag_in_loop}, 43.0),
                                           fit_of({lag_at_input}, 41.0), fit_of({damping}, 40.0)};
  const std::vector<HypothesisFit> pairs{fit_of({lag_at_bound, damping}, 47.0)};
  const std::vector<Candidate> formed = credible_pairs(singles, pairs);
  ASSERT_EQ(formed.size(), 1u);
  const auto& start = formed.front().front();
  ASSERT_EQ(start.size(), 2u);
  EXPECT_EQ(start[0].effect, Effect::kExtraLag);     // the other credible place of the lag ...
  EXPECT_EQ(start[0].place, Place::kInput);          // (the loop is where it stopped)
  EXPECT_EQ(start[1].effect, Effect::kLoadDamping);  // ... beside the same damping change

  std::vector<HypothesisFit> with_it = pairs;
  with_it.push_back(fit_of({damping, lag_at_input}, 46.0));
  EXPECT_TRUE(credible_pairs(singles, with_it).empty());  // fitted already, either order
  EXPECT_TRUE(credible_pairs(singles, {fit_of({lag_in_loop, damping}, 47.0)}).empty());
}

// Two effects in the error loop make no model (augmented_model.hpp): fitted on the worker
// threads, every thread is joined and the error reaches the caller.
TEST(Screen, AFitThatThrowsOnAWorkerIsRethrownNotFatal) {
  int blocks = 0;
  Eigen::Index warm = 0;
  const Problem pr = prepare_problem(test::null_record(5), &blocks, &warm);
  const Eigen::VectorXd base = model_output(pr, {}).yhat;
  const Candidate both_on_error{{{Effect::kDeadband, {0.1}, Place::kError, {}},
                                 {Effect::kSaturation, {1.0, 1.0, 0.01}, Place::kError, {}}}};
  DiagnoseOptions o;
  o.threads = 2;
  EXPECT_THROW(fit_all(pr, {both_on_error, both_on_error, both_on_error}, base, o),
               std::invalid_argument);
}

// The same pair reached by two of the search's routes is listed once (the report listed a
// damping change with a drift twice on a PRBS record of gensim seed 1, g057); a pair that
// differs in a parameter, a place or its span is kept.
TEST(Screen, ARepeatedHypothesisIsListedOnce) {
  const auto fit = [](double zeta, Place place, double score) {
    HypothesisFit h;
    h.effects = {{Effect::kLoadDamping, {zeta}, place, {}}, {Effect::kDrift, {5.0}}};
    h.score = score;
    return h;
  };
  std::vector<HypothesisFit> hs{fit(0.32, Place::kInput, 42.4), fit(0.32, Place::kInput, 42.4),
                                fit(0.30, Place::kInput, 41.0), fit(0.32, Place::kOutput, 40.0),
                                fit(0.32, Place::kInput, 39.0)};
  hs.back().active_from = 100;
  drop_repeats(hs);
  ASSERT_EQ(hs.size(), 4u);
  EXPECT_DOUBLE_EQ(hs[0].score, 42.4);
  EXPECT_DOUBLE_EQ(hs[1].score, 41.0);
  EXPECT_EQ(hs[2].effects[0].place, Place::kOutput);
  EXPECT_EQ(hs[3].active_from, 100);
}

// One governor, one feedback (governor_loop.hpp shared_feedback): a lag inside the governor's
// loop pairs with an effect on its error only at a place that fits the loop's feedback, and
// the two then close the loop with that feedback: the lag's own is neither used nor counted.
TEST(Pairs, ALagInTheGovernorsLoopSharesTheFeedbackOfAnEffectOnItsError) {
  const AppliedEffect lag{Effect::kExtraLag, {0.05}, Place::kGovernorLoop, {-1.0, 0.0, 0.005}};
  const AppliedEffect band{Effect::kDeadband, {0.2}, Place::kGovernorError, {0.5, 0.0, 0.005}};
  const AppliedEffect band_unity{Effect::kDeadband, {0.2}, Place::kError, {}};
  ASSERT_TRUE(pairable(lag, band));
  ASSERT_TRUE(pairable(band, lag));
  ASSERT_FALSE(pairable(lag, band_unity));  // no feedback fitted there to share
  ASSERT_FALSE(pairable(lag, lag));

  int blocks = 0;
  Eigen::Index warm = 0;
  const Problem pr = prepare_problem(test::null_record(5), &blocks, &warm);
  AppliedEffect lag_as_shared = lag;
  lag_as_shared.place_params = {0.5, 0.0, 0.005};
  const Eigen::VectorXd pair = model_output(pr, std::vector{band, lag}).yhat;
  const Eigen::VectorXd shared = model_output(pr, std::vector{band, lag_as_shared}).yhat;
  ASSERT_EQ(pair.size(), shared.size());
  EXPECT_LT((pair - shared).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + shared.cwiseAbs().maxCoeff()));
  // The lag's feedback does change the lag alone: the pair did not just ignore the lag.
  const Eigen::VectorXd own = model_output(pr, std::vector{lag}).yhat;
  const Eigen::VectorXd as_shared = model_output(pr, std::vector{lag_as_shared}).yhat;
  EXPECT_GT((own - as_shared).cwiseAbs().maxCoeff(), 1e-6 * as_shared.cwiseAbs().maxCoeff());

  HypothesisFit h;
  h.effects = {band, lag};
  HypothesisFit single;
  single.effects = {band};
  HypothesisFit lag_alone;
  lag_alone.effects = {lag};
  EXPECT_EQ(h.parameter_count(), single.parameter_count() + lag_alone.parameter_count() - 3);
}

}  // namespace
}  // namespace rig::diagnose
