#include "rig/ident/mmfm.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analytic_correlations.hpp"

namespace rig::ident {
namespace {

using testing::make_tf;
using testing::triangle_pair;

struct Case {
  const char* name;
  model::TransferFunction tf;
  model::ModelOrder order;
};

std::vector<Case> noise_free_cases() {
  return {
      {"first", make_tf({4.0}, {1.0, 2.0}), {1, 0}},
      {"second", make_tf({10.0}, {1.0, 2.0, 10.0}), {2, 0}},
      {"second_zero", make_tf({1.0, 10.0}, {1.0, 2.0, 10.0}), {2, 1}},
      {"third", make_tf({50.0}, {1.0, 7.0, 20.0, 50.0}), {3, 0}},
      {"fourth", make_tf({10.0, 290.0}, {1.0, 6.0, 47.0, 98.0, 290.0}), {4, 1}},
  };
}

void expect_coefficients_within(const model::TransferFunction& got,
                                const model::TransferFunction& want, double rel, const char* name) {
  const model::TransferFunction g = model::monic(got), w = model::monic(want);
  ASSERT_EQ(g.den.size(), w.den.size()) << name;
  ASSERT_EQ(g.num.size(), w.num.size()) << name;
  for (Eigen::Index i = 0; i < w.den.size(); ++i)
    EXPECT_NEAR(g.den(i), w.den(i), rel * std::abs(w.den(i))) << name << " den " << i;
  for (Eigen::Index i = 0; i < w.num.size(); ++i)
    EXPECT_NEAR(g.num(i), w.num(i), rel * std::abs(w.num(i))) << name << " num " << i;
}

TEST(Mmfm, NoiseFreeFirstToFourthOrderWithinPointOnePercent) {
  for (const Case& c : noise_free_cases()) {
    const auto p = triangle_pair(c.tf, 0.05, 0.01, 1000, 400);
    MmfmOptions opt;
    opt.order = c.order;
    opt.delay_s = 0.0;
    const MmfmResult r = estimate_mmfm(p.ruu, p.ryu, opt);
    expect_coefficients_within(r.model, c.tf, 1e-3, c.name);
    EXPECT_GT(r.correlation_fit_pct, 99.0) << c.name;
    EXPECT_GT(r.condition_number, 1.0) << c.name;
  }
}

TEST(Mmfm, TotalLeastSquaresAndPolynomialFamilyNoiseFree) {
  const model::TransferFunction tf = make_tf({10.0}, {1.0, 2.0, 10.0});
  const auto p = triangle_pair(tf, 0.05, 0.01, 1000, 400);
  MmfmOptions opt;
  opt.order = {2, 0};
  opt.delay_s = 0.0;
  opt.solver = MmfmSolver::kTotalLeastSquares;
  expect_coefficients_within(estimate_mmfm(p.ruu, p.ryu, opt).model, tf, 1e-3, "tls");
  opt.solver = MmfmSolver::kLeastSquares;
  opt.family = ModulatingFamily::kPolynomial;
  expect_coefficients_within(estimate_mmfm(p.ruu, p.ryu, opt).model, tf, 1e-3, "polynomial");
}

TEST(Mmfm, ThesisNormalisationB0EqualsOne) {
  // Stornoway form 1 / (q2 s^2 + q1 s + q0).
  const model::TransferFunction tf = make_tf({1.0}, {0.07, 0.19, 11.05});
  const auto p = triangle_pair(tf, 0.02, 0.005, 1000, 400);
  MmfmOptions opt;
  opt.order = {2, 0};
  opt.delay_s = 0.0;
  opt.normalisation = Normalisation::kUnitB0;
  const MmfmResult r = estimate_mmfm(p.ruu, p.ryu, opt);
  ASSERT_EQ(r.model.den.size(), 3);
  EXPECT_NEAR(r.model.num(0), 1.0, 1e-12);
  EXPECT_NEAR(r.model.den(0), 0.07, 0.07e-3);
  EXPECT_NEAR(r.model.den(1), 0.19, 0.19e-3);
  EXPECT_NEAR(r.model.den(2), 11.05, 11.05e-3);
  ASSERT_TRUE(r.derived.valid);
  EXPECT_NEAR(r.derived.fn_hz, std::sqrt(11.05 / 0.07) / (2 * M_PI), 1e-3);
}

TEST(Mmfm, FindsFractionalDeadTimeAutomatically) {
  const model::TransferFunction tf = make_tf({10.0}, {1.0, 2.0, 10.0}, 0.137);
  const auto p = triangle_pair(tf, 0.05, 0.01, 1000, 400);
  MmfmOptions opt;
  opt.order = {2, 0};
  const MmfmResult r = estimate_mmfm(p.ruu, p.ryu, opt);
  EXPECT_NEAR(r.delay_s, 0.137, 0.5e-3);
  expect_coefficients_within(r.model, tf, 2e-3, "delayed");
  EXPECT_NEAR(r.model.delay_s, r.delay_s, 1e-15);
}

TEST(Mmfm, ThesisModelOrderEffectOfAFarPole) {
  // Thesis 5-1-3: a real pole at -20 beside the pair -1+-3j still biases a second-order fit
  // (natural frequency low); letting the dead time absorb the lag removes most of it.
  const model::TransferFunction plant =
      make_tf({200.0}, {1.0, 22.0, 50.0, 200.0});  // (s^2+2s+10)(s+20)
  const auto p = triangle_pair(plant, 0.05, 0.01, 1000, 400);
  const double fn_true = std::sqrt(10.0) / (2 * M_PI);
  MmfmOptions opt;
  opt.order = {2, 0};
  opt.delay_s = 0.0;
  const MmfmResult no_delay = estimate_mmfm(p.ruu, p.ryu, opt);
  opt.delay_s.reset();
  opt.max_delay_s = 0.3;
  const MmfmResult with_delay = estimate_mmfm(p.ruu, p.ryu, opt);
  EXPECT_LT(no_delay.derived.fn_hz, 0.98 * fn_true);
  EXPECT_LT(std::abs(with_delay.derived.fn_hz - fn_true),
            0.5 * std::abs(no_delay.derived.fn_hz - fn_true));
  EXPECT_NEAR(with_delay.delay_s, 0.05, 0.01);  // about the 1/20 s lag of the far pole
  EXPECT_GT(with_delay.correlation_fit_pct, no_delay.correlation_fit_pct);
}

TEST(Mmfm, RejectsMismatchedAxesAndTooFewEquations) {
  const auto p = triangle_pair(make_tf({1.0}, {1.0, 1.0}), 0.05, 0.01, 500, 200);
  signal::Correlation other = p.ryu;
  other.zero_index = 100;
  MmfmSettings st;
  st.centres_s = {1.0};
  EXPECT_THROW(mmfm_solve(p.ruu, other, {1, 0}, 0.0, st), std::invalid_argument);
  st.functions = 2;
  EXPECT_THROW(mmfm_solve(p.ruu, p.ryu, {2, 1}, 0.0, st), std::invalid_argument);
}

}  // namespace
}  // namespace rig::ident
