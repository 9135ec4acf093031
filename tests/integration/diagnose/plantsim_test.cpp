// Concealed effects in the emulated plant (plantsim, CVODE), the model being the preset's
// linearised transfer function (plantsim/presets/stornoway.tf.json). The excitation is a
// +-3 % Gaussian bias at 100 Hz; the plant adds its own noise, drift, mains pick-up and
// firing ripple.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "plant_cases.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/model/model_file.hpp"

namespace {

rig::diagnose::DiagnoseResult diagnose_plant(const std::vector<std::string>& faults,
                                             std::uint64_t seed) {
  const char* src = std::getenv("RIG_SOURCE_DIR");
  const std::filesystem::path root = src ? src : ".";
  auto model = rig::model::read_model(root / "plantsim/presets/stornoway.tf.json");
  // The plant holds each bias for a tick (zero-order hold), which the first-order-hold
  // simulation sees as half a sample of extra dead time: part of the known recording chain.
  model.tf.delay_s += 0.005;
  const auto rec = rig::diagnose::bench::record_plant(faults, seed, seed, 200.0, 5.0);
  auto r = rig::diagnose::diagnose({model.tf, rec.u, rec.y, 0.01, std::nullopt});
  std::printf("faults [%s] seed %llu: verdict %s (validation fit %.1f %%)\n  %s\n",
              faults.empty() ? "" : faults.front().c_str(), static_cast<unsigned long long>(seed),
              r.verdict.c_str(), r.validation_fit_before_pct, r.explanation.c_str());
  for (std::size_t i = 0; i < std::min<std::size_t>(5, r.hypotheses.size()); ++i)
    std::printf("  #%zu %s: validation fit %.1f -> %.1f, score %+.2f\n", i + 1,
                r.hypotheses[i].name().c_str(), r.hypotheses[i].validation_fit_before,
                r.hypotheses[i].validation_fit_after, r.hypotheses[i].score);
  return r;
}

TEST(PlantsimDiagnose, TransducerGainErrorIsAGainChange) {
  const auto r = diagnose_plant({"meas.gain=0.9@t=0"}, 5);
  ASSERT_EQ(r.verdict, "gain_change");
  EXPECT_NEAR(r.chosen()->effects.front().params[0], 0.9, 0.9 * 0.2);
  EXPECT_GT(r.chosen()->validation_fit_after, r.chosen()->validation_fit_before);
}

TEST(PlantsimDiagnose, SlowerTransducerIsALag) {
  // 3 ms -> 80 ms transducer lag: extra_lag or sensor_lag (both name a lag of ~77 ms).
  const auto r = diagnose_plant({"meas.transducer_lag_s=0.08@t=0"}, 6);
  ASSERT_TRUE(r.verdict == "sensor_lag" || r.verdict == "extra_lag") << r.verdict;
  EXPECT_NEAR(r.chosen()->effects.front().params[0], 0.077, 0.077 * 0.2);
}

}  // namespace
