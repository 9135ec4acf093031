// Acceptance on concealed recordings (seeded; the seed of every case is printed): a smaller
// set than bench_diagnose, with its acceptance figures.
#include "concealed.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "rig/diagnose/effect_registry.hpp"

namespace rig::diagnose {
namespace {

constexpr double kDuration_s = 150.0;

TEST(Concealed, EveryEffectIsFoundWithItsParameter) {
  const Concealment cons[] = {Concealment::kNoise, Concealment::kDrift, Concealment::kAcCoupling,
                              Concealment::kPartial};
  int correct = 0, total = 0, index = 0;
  for (Effect e : kAllEffects) {
    if (!first_form(e)) continue;  // a second form of a word, not a case of its own
    ConcealedSpec spec;
    spec.effect = e;
    spec.concealment = cons[index++ % 4];
    spec.seed = 100 + static_cast<std::uint64_t>(index);
    spec.duration_s = kDuration_s;
    const ConcealedRecording rec = make_concealed(spec);
    const DiagnoseResult r = diagnose(rec.input);
    ++total;
    std::printf("%-60s -> %s\n", rec.description.c_str(), r.verdict.c_str());
    if (r.verdict != to_string(e)) {
      std::printf("  direction z %.2f: %s\n", r.location.amp.direction_z, r.explanation.c_str());
      continue;
    }
    ++correct;
    const HypothesisFit* h = r.chosen();
    ASSERT_NE(h, nullptr);
    EXPECT_GT(h->validation_fit_after, h->validation_fit_before) << rec.description;
    if (e == Effect::kDrift) continue;  // smoother time scale: not the drift's own parameter
    for (const auto& a : h->effects) {
      if (a.effect != e) continue;
      EXPECT_NEAR(a.params[0], rec.truth[0], 0.2 * std::abs(rec.truth[0]))
          << rec.description << ": " << rec.primary_param;
    }
  }
  std::printf("correct %d of %d\n", correct, total);
  EXPECT_GE(correct, static_cast<int>(std::ceil(0.9 * total)));
}

TEST(Concealed, NullCaseIsNone) {
  int none = 0;
  const int seeds = 20;
  for (int s = 0; s < seeds; ++s) {
    ConcealedSpec spec;
    spec.seed = 500 + static_cast<std::uint64_t>(s);
    spec.duration_s = kDuration_s;
    spec.concealment = s % 2 == 0 ? Concealment::kNoise : Concealment::kAcCoupling;
    const DiagnoseResult r = diagnose(make_concealed(spec).input);
    if (r.verdict == "none")
      ++none;
    else
      std::printf("false alarm, seed %llu: %s (%s)\n", static_cast<unsigned long long>(spec.seed),
                  r.verdict.c_str(), r.explanation.c_str());
  }
  EXPECT_GE(none, 19) << "of " << seeds;
}

}  // namespace
}  // namespace rig::diagnose
