#include <cmath>

#include <gtest/gtest.h>

#include "rig/ident/modulating.hpp"

namespace rig::ident {
namespace {

TEST(Modulating, HermiteDerivativeFollowsRecurrence) {
  // d/dtau phi_k = -(1/S) phi_{k+1}, checked by central differences.
  const double s = 0.3, c = 0.2, h = 1e-5;
  Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(41, -1.5, 1.9);
  const Eigen::MatrixXd f = hermite_functions(tau, c, s, 8);
  const Eigen::VectorXd tp = tau.array() + h, tm = tau.array() - h;
  const Eigen::MatrixXd fp = hermite_functions(tp, c, s, 8), fm = hermite_functions(tm, c, s, 8);
  for (int k = 0; k < 7; ++k) {
    const Eigen::VectorXd numeric = (fp.col(k) - fm.col(k)) / (2 * h);
    const Eigen::VectorXd analytic = -f.col(k + 1) / s;
    EXPECT_LT((numeric - analytic).cwiseAbs().maxCoeff(), 1e-6 * (1 + analytic.norm()))
        << "k=" << k;
  }
  EXPECT_NEAR(f(20, 0), std::exp(-0.5 * std::pow((tau(20) - c) / s, 2)), 1e-15);
}

TEST(Modulating, HermiteNegligibleOutsideHalfWidth) {
  const int k = 11;
  const double x = hermite_half_width(k);
  Eigen::VectorXd tau(2);
  tau << 0.0, x;
  const Eigen::VectorXd core = Eigen::VectorXd::LinSpaced(2001, -x, x);
  const double peak = hermite_functions(core, 0.0, 1.0, k + 1).col(k).cwiseAbs().maxCoeff();
  EXPECT_LT(std::abs(hermite_functions(tau, 0.0, 1.0, k + 1)(1, k)), 1e-9 * peak);
}

TEST(Modulating, PolynomialDerivativesVanishAtEndsAndMatchDifferences) {
  const double a = -0.4, b = 0.6, h = 1e-6;
  const int power = 4;
  Eigen::VectorXd ends(2);
  ends << a + 1e-12, b - 1e-12;
  const Eigen::MatrixXd e = polynomial_function_derivatives(ends, a, b, power, power);
  for (int i = 0; i < power; ++i) EXPECT_NEAR(e.col(i).cwiseAbs().maxCoeff(), 0.0, 1e-6);
  Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(21, a + 0.05, b - 0.05);
  const Eigen::MatrixXd d = polynomial_function_derivatives(tau, a, b, power, 2);
  const Eigen::VectorXd tp = tau.array() + h, tm = tau.array() - h;
  const Eigen::MatrixXd dp = polynomial_function_derivatives(tp, a, b, power, 2);
  const Eigen::MatrixXd dm = polynomial_function_derivatives(tm, a, b, power, 2);
  for (int i = 0; i < 2; ++i) {
    const Eigen::VectorXd numeric = (dp.col(i) - dm.col(i)) / (2 * h);
    EXPECT_LT((numeric - d.col(i + 1)).cwiseAbs().maxCoeff(), 1e-4 * d.col(i + 1).norm());
  }
  // Peak normalised to one at the window centre.
  Eigen::VectorXd mid(1);
  mid << 0.5 * (a + b);
  EXPECT_NEAR(polynomial_function_derivatives(mid, a, b, power, 0)(0, 0), 1.0, 1e-12);
}

}  // namespace
}  // namespace rig::ident
