#include "rig/fra/compare.hpp"

#include <gtest/gtest.h>

#include "second_order.hpp"

namespace rig::fra {
namespace {

// Measured points equal to the model on 0.2-10 Hz, coherence 1.
std::vector<model::FrfPoint> exact_points(const testing::SecondOrderDelay& g) {
  std::vector<model::FrfPoint> pts;
  for (double f : {0.2, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 8.0}) {
    const std::complex<double> h = g.response(f);
    model::FrfPoint p;
    p.freq_hz = f;
    p.mag = std::abs(h);
    p.phase_deg = model::wrap_deg(std::arg(h) * 180.0 / std::numbers::pi);
    p.coherence = 1.0;
    pts.push_back(p);
  }
  return pts;
}

TEST(Compare, ExactResponsePasses) {
  const testing::SecondOrderDelay g;
  const CompareResult r = compare(g, exact_points(g));  // model via its response() member
  EXPECT_EQ(r.verdict, Verdict::kPass);
  EXPECT_EQ(r.checked, 6);  // 0.5, 1, 1.5, 2, 3 and 5 Hz
}

TEST(Compare, ChecksOnlyInBandGoodPoints) {
  const testing::SecondOrderDelay g;
  auto pts = exact_points(g);
  const CompareResult r = compare(g, pts);
  int in_band = 0;
  for (const auto& row : r.rows) in_band += row.freq_hz >= 0.5 && row.freq_hz <= 5.0;
  EXPECT_EQ(r.checked, in_band);
  pts[0].mag *= 10.0;        // 0.2 Hz: outside 0.5-5 Hz, not checked
  pts[7].phase_deg += 90.0;  // 8 Hz: outside, not checked
  pts[2].mag *= 2.0;         // 1 Hz, but coherence too low
  pts[2].coherence = 0.5;
  pts[3].mag *= 2.0;  // 1.5 Hz, but the estimator marked it invalid
  pts[3].valid = false;
  const CompareResult r2 = compare(g, pts);
  EXPECT_EQ(r2.verdict, Verdict::kPass) << r2.summary;
  EXPECT_EQ(r2.checked, in_band - 2);
  EXPECT_FALSE(r2.rows[0].checked);
  EXPECT_NEAR(r2.rows[0].mag_error_db, 20.0, 1e-9);
}

TEST(Compare, MagnitudeAndPhaseTolerances) {
  const testing::SecondOrderDelay g;
  auto pts = exact_points(g);
  pts[4].mag *= std::pow(10.0, 0.9 / 20.0);  // +0.9 dB at 2 Hz: inside +-1 dB
  pts[5].phase_deg = model::wrap_deg(pts[5].phase_deg - 4.9);
  CompareResult r = compare(g, pts);
  EXPECT_EQ(r.verdict, Verdict::kPass) << r.summary;
  EXPECT_NEAR(r.rows[4].mag_error_db, 0.9, 1e-9);
  EXPECT_NEAR(r.rows[5].phase_error_deg, -4.9, 1e-9);

  pts[4].mag *= std::pow(10.0, 0.2 / 20.0);  // now +1.1 dB
  r = compare(g, pts);
  EXPECT_EQ(r.verdict, Verdict::kFail);
  EXPECT_EQ(r.failed, 1);
  EXPECT_FALSE(r.rows[4].pass);
  EXPECT_NEAR(r.max_abs_mag_error_db, 1.1, 1e-9);

  CompareTolerances loose;
  loose.mag_db = 1.5;
  EXPECT_EQ(compare(g, pts, loose).verdict, Verdict::kPass);
}

TEST(Compare, PhaseErrorIsWrapped) {
  // A model at -179 deg and a measurement at +178 deg differ by 3 deg, not 357.
  const ResponseFn model = [](double) {
    return std::polar(1.0, -179.0 * std::numbers::pi / 180.0);
  };
  std::vector<model::FrfPoint> pts;
  for (double f : {1.0, 2.0, 3.0}) pts.push_back({f, 1.0, 178.0, 1.0});
  pts[1].phase_deg = 178.0 - 720.0;  // unwrapped measurement, two turns down
  const CompareResult r = compare(model, pts);
  EXPECT_EQ(r.verdict, Verdict::kPass) << r.summary;
  for (const auto& row : r.rows) EXPECT_NEAR(row.phase_error_deg, -3.0, 1e-9);
  pts[2].phase_deg = 170.0;  // -11 deg after wrapping
  EXPECT_EQ(compare(model, pts).verdict, Verdict::kFail);
}

TEST(Compare, TooFewGoodPointsIsInsufficient) {
  const testing::SecondOrderDelay g;
  auto pts = exact_points(g);
  for (auto& p : pts) p.coherence = 0.3;
  pts[4].coherence = 0.99;
  const CompareResult r = compare(g, pts);
  EXPECT_EQ(r.checked, 1);
  EXPECT_EQ(r.verdict, Verdict::kInsufficient);
  EXPECT_THROW(compare(ResponseFn{}, pts), std::invalid_argument);
}

}  // namespace
}  // namespace rig::fra
