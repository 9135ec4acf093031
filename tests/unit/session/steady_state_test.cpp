#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "rig/session/steady_state.hpp"

namespace rig::session {
namespace {

struct Record {
  std::vector<double> t, p;
};

// P = p0 + slope t + N(0, sigma), 100 Hz for `duration` seconds, seeded.
Record make_record(double p0, double slope, double sigma, double duration, unsigned seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  Record r;
  for (int i = 0; i <= static_cast<int>(duration * 100); ++i) {
    const double t = i * 0.01;
    r.t.push_back(t);
    r.p.push_back(p0 + slope * t + noise(gen));
  }
  return r;
}

TEST(SteadyState, QuietSetPassesWithMeanPowerAndMeasuredNoise) {
  const Record r = make_record(3500.0, 0.0, 3.5, 10.0, 7);  // 0.1 % noise
  const auto res = check_steady_state(r.t, r.p, {0.5, 0.5, 1.0});
  EXPECT_TRUE(res.ok) << res.reason;
  EXPECT_NEAR(res.p0_kw, 3500.0, 0.5);
  EXPECT_NEAR(res.noise_pct, 0.1, 0.01);
  EXPECT_LT(res.drift_pct, 0.05);
}

TEST(SteadyState, DriftAboveTheLimitRefusesWithTheReason) {
  const Record r = make_record(3500.0, 3.5, 1.0, 10.0, 8);  // 35 kW over 10 s = 1 %
  const auto res = check_steady_state(r.t, r.p, {0.5, 0.5, 1.0});
  EXPECT_FALSE(res.ok);
  EXPECT_NEAR(res.drift_pct, 1.0, 0.05);
  EXPECT_NE(res.reason.find("drift"), std::string::npos) << res.reason;
}

TEST(SteadyState, NoiseAboveTheLimitRefuses) {
  const Record r = make_record(3500.0, 0.0, 35.0, 10.0, 9);  // 1 % noise
  const auto res = check_steady_state(r.t, r.p, {0.5, 0.5, 1.0});
  EXPECT_FALSE(res.ok);
  EXPECT_NE(res.reason.find("noise"), std::string::npos) << res.reason;
}

TEST(SteadyState, NanOrUnloadedSetRefuses) {
  Record r = make_record(3500.0, 0.0, 1.0, 2.0, 10);
  r.p[50] = std::nan("");
  EXPECT_FALSE(check_steady_state(r.t, r.p, {}).ok);
  const Record idle = make_record(0.0, 0.0, 0.01, 2.0, 11);
  const auto res = check_steady_state(idle.t, idle.p, {});
  EXPECT_FALSE(res.ok);
  EXPECT_NE(res.reason.find("not above"), std::string::npos);
}

}  // namespace
}  // namespace rig::session
