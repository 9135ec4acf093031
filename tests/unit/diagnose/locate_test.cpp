#include <gtest/gtest.h>

#include "concealed.hpp"
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

}  // namespace
}  // namespace rig::diagnose
