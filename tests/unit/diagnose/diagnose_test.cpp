#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "concealed.hpp"

namespace rig::diagnose {
namespace {

DiagnoseInput good_input() {
  ConcealedSpec spec;
  spec.duration_s = 60.0;
  return make_concealed(spec).input;
}

void expect_one_line_error(const DiagnoseInput& in, const std::string& fragment) {
  try {
    diagnose(in);
    FAIL() << "no error for " << fragment;
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(DiagnoseInputCheck, RejectsNonFiniteSamples) {
  DiagnoseInput in = good_input();
  in.y(100) = std::numeric_limits<double>::quiet_NaN();
  expect_one_line_error(in, "sample 100");
  in = good_input();
  in.u(7) = std::numeric_limits<double>::infinity();
  expect_one_line_error(in, "sample 7");
}

TEST(DiagnoseInputCheck, RejectsUnstableAndImproperModels) {
  DiagnoseInput in = good_input();
  in.model.den = Eigen::Vector3d(1.0, -0.5, 4.0);
  expect_one_line_error(in, "unstable");
  in = good_input();
  in.model.num = Eigen::VectorXd::Ones(5);
  expect_one_line_error(in, "improper");
}

TEST(DiagnoseInputCheck, RejectsShortOrMismatchedRecords) {
  DiagnoseInput in = good_input();
  in.u.conservativeResize(200);
  in.y.conservativeResize(200);
  expect_one_line_error(in, "too short to split");
  in = good_input();
  in.y.conservativeResize(in.y.size() - 1);
  expect_one_line_error(in, "differ in length");
}

TEST(Diagnose, PairIsTriedWhenDriftMasksAnEffect) {
  ConcealedSpec spec;
  spec.effect = Effect::kGainChange;
  spec.concealment = Concealment::kDrift;
  spec.seed = 31;
  spec.duration_s = 200.0;
  const ConcealedRecording rec = make_concealed(spec);
  const DiagnoseResult r = diagnose(rec.input);
  ASSERT_EQ(r.verdict, "gain_change") << r.explanation;
  ASSERT_NE(r.chosen(), nullptr);
  EXPECT_NEAR(r.chosen()->effects.front().params[0], 0.85, 0.85 * 0.2);
  EXPECT_NE(r.explanation.find("gain"), std::string::npos);
}

}  // namespace
}  // namespace rig::diagnose
