// A nonlinearity on the governor's error (placement.hpp "error", error_loop.hpp): the
// stepped loop against an independently integrated one, and a deadband there found by
// diagnose() at that place.
#include "rig/diagnose/error_loop.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "records.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/placement.hpp"

namespace rig::diagnose {
namespace {

using test::null_record;
using test::rms;
using test::white;

// A governor loop that tracks the bias: L = k / (s (1 + s T)) with unity feedback, so the
// closed loop is G = k / (T s^2 + s + k), static gain 1.
constexpr double kLoopGain = 2.0 * 3.14159265358979 * 0.4;  // crossover near 0.4 Hz
constexpr double kLoopLagS = 0.15;

model::TransferFunction closed_loop() {
  model::TransferFunction g;
  g.num = Eigen::VectorXd::Constant(1, kLoopGain);
  g.den = Eigen::Vector3d(kLoopLagS, 1.0, kLoopGain);
  return g;
}

// The loop with N on its error, integrated with RK4 on 40 sub-steps per sample (the input
// linear between samples): x1' = x2... written as y' = v, v' = (k N(e) - v) / T, e = u - y.
Eigen::VectorXd integrated_loop(const Eigen::VectorXd& u, double dt_s,
                                const std::function<double(double)>& n) {
  constexpr int kSub = 40;
  const double h = dt_s / kSub;
  double y = 0.0, v = 0.0;
  Eigen::VectorXd out(u.size());
  auto f = [&](double t_frac, Eigen::Index k, double yy, double vv, double* dy, double* dv) {
    const double uk = k + 1 < u.size() ? u(k) + t_frac * (u(k + 1) - u(k)) : u(k);
    *dy = vv;
    *dv = (kLoopGain * n(uk - yy) - vv) / kLoopLagS;
  };
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    out(k) = y;
    for (int i = 0; i < kSub; ++i) {
      const double t0 = static_cast<double>(i) / kSub, th = 0.5 / kSub, t1 = 1.0 / kSub;
      double a1, b1, a2, b2, a3, b3, a4, b4;
      f(t0, k, y, v, &a1, &b1);
      f(t0 + th, k, y + 0.5 * h * a1, v + 0.5 * h * b1, &a2, &b2);
      f(t0 + th, k, y + 0.5 * h * a2, v + 0.5 * h * b2, &a3, &b3);
      f(t0 + t1, k, y + h * a3, v + h * b3, &a4, &b4);
      y += h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4);
      v += h / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4);
    }
  }
  return out;
}

TEST(ErrorLoop, TheIdentityLeavesTheBaseline) {
  const DiagnoseInput in = null_record(61);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd z0 = model::simulate(in.model, u, in.dt_s);
  const Eigen::VectorXd y =
      close_error_loop(in.model, u, z0, in.model.dc_gain(), in.dt_s, [](double e) { return e; });
  EXPECT_LT((y - z0).cwiseAbs().maxCoeff(), 1e-12 * rms(z0));
}

TEST(ErrorLoop, ADeadbandOnTheErrorMatchesTheIntegratedLoop) {
  // A commissioning excitation (band-limited: the deadband acts on the samples' hold).
  const DiagnoseInput in = null_record(62);
  const double dt_s = in.dt_s;
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd e0 = u - model::simulate(closed_loop(), u, dt_s);
  const double w = 0.5 * rms(e0);
  const auto db = [w](double e) { return e > w ? e - w : e < -w ? e + w : 0.0; };
  const Eigen::VectorXd reference = integrated_loop(u, dt_s, db);
  const Eigen::VectorXd z0 = model::simulate(closed_loop(), u, dt_s);
  const Eigen::VectorXd y = close_error_loop(closed_loop(), u, z0, 1.0, dt_s, db);
  // The deadband changes the output by a share of its rms; the stepped loop reproduces it.
  ASSERT_GT(rms(reference - z0), 0.05 * rms(reference));
  EXPECT_LT(rms(y - reference), 0.01 * rms(reference - z0));
}

TEST(ErrorLoop, AGovernorErrorDeadbandIsFoundOnTheError) {
  DiagnoseInput in = null_record(63);
  in.model = closed_loop();
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd e0 = u - model::simulate(in.model, u, in.dt_s);
  const double w = 0.4 * rms(e0);
  const Eigen::VectorXd y = integrated_loop(u, in.dt_s, [w](double e) {
    return e > w ? e - w : e < -w ? e + w : 0.0;
  });
  in.y = y + white(y.size(), 0.1 * rms(y), 13);
  const DiagnoseResult r = diagnose(in);
  ASSERT_EQ(r.verdict, "deadband") << r.explanation;
  const AppliedEffect& e = r.chosen()->effects.front();
  EXPECT_EQ(e.place, Place::kError) << r.explanation;
  EXPECT_NEAR(e.params[0], w, 0.2 * w) << r.explanation;
  EXPECT_NE(r.explanation.find("the governor holds its output"), std::string::npos)
      << r.explanation;
}

}  // namespace
}  // namespace rig::diagnose
