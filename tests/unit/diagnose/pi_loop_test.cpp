// A nonlinearity after the governor's PI, inside its loop (placement.hpp "pi_loop",
// error_loop.hpp pi_loop_on_error): the stepped loop against an independently integrated
// one, and an actuator hysteresis there found by diagnose() at that place.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <span>

#include "records.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/error_loop.hpp"
#include "rig/diagnose/placement.hpp"

namespace rig::diagnose {
namespace {

using test::null_record;
using test::rms;
using test::white;

// A PI governor on the error of a unity-feedback loop, a = kp (e + xi / Ti), xi' = e, its
// output through the actuator N onto a plant lag y' = (N(a) - y) / Tp.
constexpr double kKp = 1.5;
constexpr double kTiS = 0.4;
constexpr double kTpS = 0.3;

// The closed loop G = kp (Ti s + 1) / (Ti Tp s^2 + Ti (1 + kp) s + kp), static gain 1; with
// an output filter 1 / (1 + s Tf) after the PI,
// G = kp (Ti s + 1) / (Ti Tf Tp s^3 + Ti (Tf + Tp) s^2 + Ti (1 + kp) s + kp).
model::TransferFunction closed_loop(double filter_s = 0.0) {
  model::TransferFunction g;
  g.num = Eigen::Vector2d(kKp * kTiS, kKp);
  if (filter_s > 0.0)
    g.den =
        Eigen::Vector4d(kTiS * filter_s * kTpS, kTiS * (filter_s + kTpS), kTiS * (1.0 + kKp), kKp);
  else
    g.den = Eigen::Vector3d(kTiS * kTpS, kTiS * (1.0 + kKp), kKp);
  return g;
}

// The actuator stepped on every sub-step (its state kept), the output filter and the plant
// integrated exactly over each sub-step for their inputs held, 100 sub-steps per sample, the
// input linear between samples.
Eigen::VectorXd integrated_loop(const Eigen::VectorXd& u, double dt_s,
                                const std::function<double(double)>& actuator,
                                double filter_s = 0.0) {
  constexpr int kSub = 100;
  const double h = dt_s / kSub, decay = std::exp(-h / kTpS);
  const double filter_decay = filter_s > 0.0 ? std::exp(-h / filter_s) : 0.0;
  double y = 0.0, xi = 0.0, f = 0.0;
  Eigen::VectorXd out(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    out(k) = y;
    for (int i = 0; i < kSub; ++i) {
      const double t = (i + 0.5) / kSub;
      const double uk = k + 1 < u.size() ? u(k) + t * (u(k + 1) - u(k)) : u(k);
      const double e = uk - y;
      xi += e * h;
      f = kKp * (e + xi / kTiS) + (f - kKp * (e + xi / kTiS)) * filter_decay;
      const double rack = actuator(f);
      y = rack + (y - rack) * decay;
    }
  }
  return out;
}

// The loop's PI output on the linear loop's error (the actuator's signal without the effect).
Eigen::VectorXd linear_pi_output(const Eigen::VectorXd& u, double dt_s) {
  const Eigen::VectorXd e = u - model::simulate(closed_loop(), u, dt_s);
  Eigen::VectorXd a(e.size());
  double sum = 0.0;
  for (Eigen::Index i = 0; i < e.size(); ++i) a(i) = kKp * (e(i) + (sum += e(i)) * dt_s / kTiS);
  return a;
}

TEST(PiLoop, TheIdentityLeavesTheBaseline) {
  const DiagnoseInput in = null_record(71);
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const Eigen::VectorXd z0 = model::simulate(closed_loop(), u, in.dt_s);
  const auto identity = [](StepState&, double x) { return x; };
  const Eigen::VectorXd y = close_error_loop(closed_loop(), u, z0, 1.0, in.dt_s,
                                             pi_loop_on_error(identity, kKp, {kTiS, 0.0}, in.dt_s));
  EXPECT_LT((y - z0).cwiseAbs().maxCoeff(), 1e-12 * rms(z0));
}

// A rack limit after the PI: the loop's integrator keeps pushing against it, unlike a limit
// on the bias; the stepped loop reproduces the integrated one.
TEST(PiLoop, ALimitAfterThePiMatchesTheIntegratedLoop) {
  const DiagnoseInput in = null_record(72);
  const double dt_s = in.dt_s;
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const double w = 1.2 * rms(linear_pi_output(u, dt_s));
  const auto clamp = [w](double a) { return std::clamp(a, -w, w); };
  const Eigen::VectorXd reference = integrated_loop(u, dt_s, clamp);
  const Eigen::VectorXd z0 = model::simulate(closed_loop(), u, dt_s);
  const auto step = [&](StepState&, double a) { return clamp(a); };
  const Eigen::VectorXd y = close_error_loop(closed_loop(), u, z0, 1.0, dt_s,
                                             pi_loop_on_error(step, kKp, {kTiS, 0.0}, dt_s));
  // The same limit on the bias itself: another shape.
  const Eigen::VectorXd on_bias = model::simulate(closed_loop(), u.cwiseMax(-w).cwiseMin(w), dt_s);
  std::printf("limit after the PI: stepped %.4f, on the bias %.3f of its effect\n",
              rms(y - reference) / rms(reference - z0),
              rms(on_bias - reference) / rms(reference - z0));
  ASSERT_GT(rms(reference - z0), 0.05 * rms(reference));
  EXPECT_GT(rms(on_bias - reference), 0.3 * rms(reference - z0));
  EXPECT_LT(rms(y - reference), 0.05 * rms(reference - z0));
}

// The same with the governor's output filter between the PI and the limit: the stepped loop
// inverts the filter exactly in discrete time.
TEST(PiLoop, ALimitAfterAFilteredPiMatchesTheIntegratedLoop) {
  const DiagnoseInput in = null_record(74);
  const double dt_s = in.dt_s, filter_s = 0.08;
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const double w = 1.2 * rms(linear_pi_output(u, dt_s));
  const auto clamp = [w](double a) { return std::clamp(a, -w, w); };
  const Eigen::VectorXd reference = integrated_loop(u, dt_s, clamp, filter_s);
  const Eigen::VectorXd z0 = model::simulate(closed_loop(filter_s), u, dt_s);
  const auto step = [&](StepState&, double a) { return clamp(a); };
  const Eigen::VectorXd y = close_error_loop(closed_loop(filter_s), u, z0, 1.0, dt_s,
                                             pi_loop_on_error(step, kKp, {kTiS, filter_s}, dt_s));
  // Without the filter in the place: another shape.
  const Eigen::VectorXd unfiltered = close_error_loop(
      closed_loop(filter_s), u, z0, 1.0, dt_s, pi_loop_on_error(step, kKp, {kTiS, 0.0}, dt_s));
  std::printf("limit after the filtered PI: stepped %.4f, without the filter %.3f of its effect\n",
              rms(y - reference) / rms(reference - z0),
              rms(unfiltered - reference) / rms(reference - z0));
  ASSERT_GT(rms(reference - z0), 0.05 * rms(reference));
  EXPECT_GT(rms(unfiltered - reference), 0.2 * rms(reference - z0));
  EXPECT_LT(rms(y - reference), 0.05 * rms(reference - z0));
}

// gensim's actuator: a Bouc-Wen loop, 30 % linear, after the PI.
TEST(PiLoop, AnActuatorHysteresisIsFoundAfterThePi) {
  DiagnoseInput in = null_record(73);
  in.model = closed_loop();
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const double z0 = 0.5 * rms(linear_pi_output(u, in.dt_s));
  double z = 0.0, last = 0.0;
  const Eigen::VectorXd y = integrated_loop(u, in.dt_s, [&](double a) {
    z = bouc_wen_step(z, a - last, z0, 1.0);
    last = a;
    return 0.3 * a + 0.7 * z;
  });
  in.y = y + white(y.size(), 0.1 * rms(y), 23);
  const DiagnoseResult r = diagnose(in);
  ASSERT_TRUE(r.verdict == "hysteresis" || r.verdict == "backlash") << r.explanation;
  const AppliedEffect& e = r.chosen()->effects.front();
  EXPECT_EQ(e.place, Place::kPiLoop) << r.explanation;
  EXPECT_NEAR(e.place_params.at(0), kTiS, 0.3 * kTiS) << r.explanation;
  EXPECT_NE(r.explanation.find("after the governor's PI"), std::string::npos) << r.explanation;
}

}  // namespace
}  // namespace rig::diagnose
