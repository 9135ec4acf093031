#include "rig/session/amplitude_plan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "sim.hpp"

namespace rig::session {
namespace {

TEST(AmplitudePlan, PilotGainRemovesNoisePower) {
  // Response rms 5 kW of which 3 kW is noise: 4 kW caused by 0.1 % rms -> 40 kW per %.
  EXPECT_NEAR(pilot_gain_rms({0.1, 5.0, 3.0}), 40.0, 1e-12);
  EXPECT_DOUBLE_EQ(pilot_gain_rms({0.1, 2.0, 3.0}), 0.0);  // noise-dominated pilot
  EXPECT_THROW(pilot_gain_rms({0.0, 5.0, 3.0}), std::invalid_argument);
  EXPECT_THROW(pilot_gain_rms({0.1, std::nan(""), 3.0}), std::invalid_argument);
}

TEST(AmplitudePlan, PriorGainOfFlatAndResonantModels) {
  EXPECT_NEAR(prior_gain_rms([](double) { return 7.0; }, 4.0), 7.0, 1e-9);
  // |G| = f on [0, B]: g^2 = B^2 / 3.
  EXPECT_NEAR(prior_gain_rms([](double f) { return f; }, 3.0), std::sqrt(3.0), 1e-5);
  const testing::PlantParams p;
  const double g = prior_gain_rms([&p](double f) { return p.magnitude(f); }, 4.0);
  // Between the static gain and the resonance peak (5 x static).
  EXPECT_GT(g, p.gain_kw_per_pct);
  EXPECT_LT(g, 5.0 * p.gain_kw_per_pct);
}

TEST(AmplitudePlan, PredictedPeakIsEightyPercentOfBand) {
  AmplitudePlanOptions o;
  o.band_kw = 105.0;
  o.max_excitation_rms_pct = 10.0;
  const AmplitudePlan plan = plan_excitation(50.0, 2.0, o);
  ASSERT_TRUE(plan.feasible) << plan.reason;
  // e = (0.8 * 105 / 4 - 2) / (1.25 * 50)
  EXPECT_NEAR(plan.excitation_rms_pct, (21.0 - 2.0) / 62.5, 1e-12);
  EXPECT_NEAR(plan.predicted_peak_kw, 0.8 * 105.0, 1e-9);
  o.max_excitation_rms_pct = 0.1;
  const AmplitudePlan capped = plan_excitation(50.0, 2.0, o);
  EXPECT_DOUBLE_EQ(capped.excitation_rms_pct, 0.1);
  EXPECT_LT(capped.predicted_peak_kw, 0.8 * 105.0);
}

TEST(AmplitudePlan, NoiseFillingTheBandIsInfeasible) {
  AmplitudePlanOptions o;
  o.band_kw = 105.0;
  const AmplitudePlan plan = plan_excitation(50.0, 21.0, o);  // 4 x 21 = 84 = 80 % of band
  EXPECT_FALSE(plan.feasible);
  EXPECT_NE(plan.reason.find("noise"), std::string::npos) << plan.reason;
  o.band_kw = 0.0;
  EXPECT_THROW(plan_excitation(50.0, 1.0, o), std::invalid_argument);
}

}  // namespace
}  // namespace rig::session
