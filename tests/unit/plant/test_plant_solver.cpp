// CVODE wrapper: accuracy against an analytic second-order response, typed errors.
#include <cvode/cvode.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "plantsim/solver/cvode_solver.hpp"

namespace plantsim {
namespace {

// x'' + 2 zeta wn x' + wn^2 x = wn^2 (unit step at t = 0, x(0) = x'(0) = 0):
// x(t) = 1 - e^{-zeta wn t} (cos(wd t) + zeta wn / wd sin(wd t)), wd = wn sqrt(1 - zeta^2).
class SecondOrder : public OdeSystem {
 public:
  SecondOrder(double wn, double zeta) : wn_(wn), zeta_(zeta) {}
  int size() const override { return 2; }
  bool derivatives(double, const double* x, double* dx) override {
    dx[0] = x[1];
    dx[1] = wn_ * wn_ * (1.0 - x[0]) - 2.0 * zeta_ * wn_ * x[1];
    return true;
  }
  double exact(double t) const {
    const double wd = wn_ * std::sqrt(1.0 - zeta_ * zeta_);
    return 1.0 -
           std::exp(-zeta_ * wn_ * t) * (std::cos(wd * t) + zeta_ * wn_ / wd * std::sin(wd * t));
  }

 private:
  double wn_, zeta_;
};

double max_error(double rtol, double atol) {
  SecondOrder sys(2.0 * std::numbers::pi * 2.0, 0.1);
  SolverOptions opts;
  opts.rtol = rtol;
  opts.atol = atol;
  CvodeSolver solver(sys, 0.0, Eigen::Vector2d::Zero(), opts);
  double err = 0.0;
  for (int k = 1; k <= 5000; ++k) {  // 5 s in 1 ms ticks, as the plant is stepped
    solver.advance_to(k * 1e-3);
    EXPECT_DOUBLE_EQ(solver.time(), k * 1e-3);
    err = std::max(err, std::abs(solver.state()[0] - sys.exact(k * 1e-3)));
  }
  return err;
}

TEST(PlantSolver, MatchesAnalyticSecondOrderStep) {
  // Overshoot of this step is 73 %; errors are absolute on a unit step.
  EXPECT_LT(max_error(1e-6, 1e-8), 1e-4);
  EXPECT_LT(max_error(1e-10, 1e-12), 1e-7);
}

TEST(PlantSolver, TighterToleranceIsMoreAccurate) {
  EXPECT_LT(max_error(1e-9, 1e-11), max_error(1e-5, 1e-7));
}

class Failing : public OdeSystem {
 public:
  int size() const override { return 1; }
  bool derivatives(double t, const double*, double* dx) override {
    dx[0] = 1.0;
    return t < 0.5;  // the right-hand side fails from t = 0.5 on
  }
};

TEST(PlantSolver, RhsFailureBecomesTypedSolverError) {
  Failing sys;
  CvodeSolver solver(sys, 0.0, Eigen::VectorXd::Zero(1), SolverOptions{});
  solver.advance_to(0.4);
  EXPECT_NEAR(solver.state()[0], 0.4, 1e-9);
  try {
    solver.advance_to(1.0);
    FAIL() << "expected SolverError";
  } catch (const SolverError& e) {
    EXPECT_EQ(e.function(), "CVode");
    EXPECT_LT(e.code(), 0);
    EXPECT_NE(std::string(e.what()).find("CV_"), std::string::npos) << e.what();
  }
}

TEST(PlantSolver, CheckRetvalPassesSuccessAndNamesFailures) {
  EXPECT_NO_THROW(check_retval(CV_SUCCESS, "CVode"));
  EXPECT_NO_THROW(check_retval(CV_TSTOP_RETURN, "CVode"));
  try {
    check_retval(CV_TOO_MUCH_WORK, "CVode");
    FAIL();
  } catch (const SolverError& e) {
    EXPECT_EQ(e.code(), CV_TOO_MUCH_WORK);
    EXPECT_NE(std::string(e.what()).find("CV_TOO_MUCH_WORK"), std::string::npos) << e.what();
  }
}

TEST(PlantSolver, ReinitRestartsFromGivenState) {
  SecondOrder sys(1.0, 0.5);
  CvodeSolver solver(sys, 0.0, Eigen::Vector2d::Zero(), SolverOptions{});
  solver.advance_to(1.0);
  solver.reinit(1.0, Eigen::Vector2d::Zero());
  solver.advance_to(2.0);
  // From rest again, so x(2) equals the analytic response at age 1 s.
  EXPECT_NEAR(solver.state()[0], sys.exact(1.0), 1e-5);
}

}  // namespace
}  // namespace plantsim
