#include "rig/fra/h1.hpp"

#include <gtest/gtest.h>

#include <random>

#include "rig/fra/compare.hpp"
#include "second_order.hpp"

namespace rig::fra {
namespace {

constexpr double kDt = 0.01;

TEST(H1, RecoversKnownSystemWhereCoherenceIsHighAndFlagsNoise) {
  const testing::SecondOrderDelay g;
  testing::DiscretePlant plant(g, kDt);
  const unsigned seed = 2024;
  std::mt19937 rng(seed);
  std::normal_distribution<double> excitation(0.0, 0.3);  // % of rated, white
  std::normal_distribution<double> noise(0.0, 0.5);       // kW, white measurement noise
  const Eigen::Index n = 120000;                          // 1200 s at 100 Hz
  Eigen::VectorXd u(n), y(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    u(k) = excitation(rng);
    y(k) = 3500.0 + plant.step(u(k)) + noise(rng);
  }
  WelchOptions o;
  o.segment_length = 4096;  // 0.024 Hz bins: 16 across the resonance's half-power width
  const auto frf = h1_estimate(u, y, kDt, o);
  SCOPED_TRACE("seed " + std::to_string(seed));
  ASSERT_EQ(frf.size(), 2048u);  // bins 1..2048 of a 4096-point segment
  // Against the exact discrete response with the commissioning tolerances (+-1 dB, +-5 deg
  // over 0.5-5 Hz) wherever the coherence is high. Random error at gamma^2 >= 0.95 with 57
  // segments: eps = sqrt(1 - g2) / (g sqrt(2 M)) <= 0.021 (0.19 dB, 1.2 deg) at the worst
  // point and far less at most; resolution bias at the resonance is < 0.1 dB.
  CompareTolerances tol;
  tol.min_coherence = 0.95;
  const ResponseFn truth = [&plant](double f) { return plant.response(f); };
  const CompareResult cmp = compare(truth, frf, tol);
  EXPECT_EQ(cmp.verdict, Verdict::kPass) << cmp.summary;
  EXPECT_GT(cmp.checked, 150) << cmp.summary;  // of 185 bins in 0.5-5 Hz
  EXPECT_LT(cmp.max_abs_mag_error_db, 0.5) << cmp.summary;
  double coh_low = 0.0, coh_high = 0.0;
  int n_low = 0, n_high = 0;
  for (const model::FrfPoint& p : frf) {
    if (p.freq_hz >= 0.5 && p.freq_hz <= 5.0) {
      coh_low += p.coherence;
      ++n_low;
    }
    if (p.freq_hz >= 30.0 && p.freq_hz <= 45.0) {
      coh_high += p.coherence;
      ++n_high;
    }
  }
  EXPECT_GT(coh_low / n_low, 0.95);   // response dominates the noise
  EXPECT_LT(coh_high / n_high, 0.3);  // noise dominates the attenuated response
}

TEST(H1, RejectsBadRecords) {
  const Eigen::VectorXd a = Eigen::VectorXd::Zero(100);
  EXPECT_THROW(h1_estimate(a, Eigen::VectorXd::Zero(99), kDt), std::invalid_argument);
  EXPECT_THROW(h1_estimate(a, a, kDt), std::invalid_argument);  // shorter than one segment
  WelchOptions o;
  o.segment_length = 64;
  o.overlap = 0.95;
  EXPECT_THROW(h1_estimate(a, a, kDt, o), std::invalid_argument);
}

TEST(H1, SegmentCountFollowsOverlap) {
  const Eigen::VectorXd u = Eigen::VectorXd::Random(4096);
  WelchOptions o;
  o.segment_length = 1024;
  EXPECT_EQ(welch_cross_spectra(u, u, kDt, o).segments, 7);  // hop 512: (4096-1024)/512 + 1
  o.overlap = 0.0;
  EXPECT_EQ(welch_cross_spectra(u, u, kDt, o).segments, 4);
}

}  // namespace
}  // namespace rig::fra
