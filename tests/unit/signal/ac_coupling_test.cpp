#include "rig/signal/ac_coupling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "test_data.hpp"

namespace rig::signal {
namespace {

// Unit step into s RC / (1 + s RC): v(t) = exp(-t / RC); sampled just after t = k dt.
TEST(AcCoupling, StepResponseIsTheAnalogueExponential) {
  const double dt_s = 0.01, rc_s = 1.0 / (2.0 * std::numbers::pi * 0.1);
  const Eigen::VectorXd v = ac_couple(Eigen::VectorXd::Ones(2000), dt_s, rc_s);
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    ASSERT_NEAR(v[k], std::exp(-k * dt_s / rc_s), 1e-13) << "k " << k;
  }
}

// A ZOH staircase is a sum of steps (x_j - x_{j-1}) at t_j, so the analogue output just after
// t_k is v(t_k) = sum_{j<=k} (x_j - x_{j-1}) exp(-(t_k - t_j)/RC): superposition, evaluated
// here term by term, independently of the recursion.
TEST(AcCoupling, StaircaseMatchesAnalogueSuperposition) {
  const double dt_s = 0.05, rc_s = 0.7;
  const Eigen::VectorXd x = test::white(400, 201).array() + 3.0;  // with a DC offset
  const Eigen::VectorXd v = ac_couple(x, dt_s, rc_s);
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    double analogue = 0.0;
    for (Eigen::Index j = 0; j <= k; ++j) {
      const double step = x[j] - (j > 0 ? x[j - 1] : 0.0);
      analogue += step * std::exp(-static_cast<double>(k - j) * dt_s / rc_s);
    }
    ASSERT_NEAR(v[k], analogue, 1e-11) << "k " << k;
  }
  // The DC offset is blocked: late samples average to ~0 although x averages to 3.
  EXPECT_NEAR(v.tail(200).mean(), 0.0, 0.2);
}

// Matched coupling: the coupler is LTI, so coupling the response of a system equals the
// system's response to the coupled excitation (R_vw = H R_ww in MMFM.md section 6).
TEST(AcCoupling, CouplingCommutesWithTheSystem) {
  const Eigen::VectorXd u = test::white(1000, 211);
  const Eigen::Vector4d h(0.0, 0.3, 1.0, 0.5);
  const Eigen::VectorXd lhs = ac_couple(test::fir(h, u), 0.01, 1.5);
  const Eigen::VectorXd rhs = test::fir(h, ac_couple(u, 0.01, 1.5));
  EXPECT_LT((lhs - rhs).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(AcCoupling, StreamingBlocksEqualTheVectorFunctionAndSettledResetGivesZero) {
  const Eigen::VectorXd x = test::white(900, 221);
  AcCoupler coupler(0.01, 2.0);
  Eigen::VectorXd streamed(900);
  streamed << coupler.process(x.head(100)), coupler.process(x.segment(100, 1)),
      coupler.process(x.tail(799));
  EXPECT_EQ((streamed - ac_couple(x, 0.01, 2.0)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_DOUBLE_EQ(coupler.pole(), std::exp(-0.01 / 2.0));

  coupler.reset(5.0);  // settled at a constant input of 5
  for (int i = 0; i < 10; ++i) EXPECT_EQ(coupler.step(5.0), 0.0);
  EXPECT_NEAR(rc_from_corner_hz(0.1), 1.5915494309189535, 1e-15);
}

TEST(AcCoupling, BadArgumentsAreRejected) {
  EXPECT_THROW(AcCoupler(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(AcCoupler(0.01, -1.0), std::invalid_argument);
  EXPECT_THROW(rc_from_corner_hz(0.0), std::invalid_argument);
}

}  // namespace
}  // namespace rig::signal
