// A nonlinearity on the governor's error (placement.hpp "error", error_loop.hpp): the
// stepped loop against an independently integrated one, and a deadband there found by
// diagnose() at that place.
#include "rig/diagnose/error_loop.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <span>
#include <vector>

#include "records.hpp"
#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/report_out.hpp"
#include "rig/diagnose/verdict.hpp"
#include "rig/model/model_file.hpp"

namespace rig::diagnose {
namespace {

using test::null_record;
using test::rms;
using test::two_level;
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

// The loop with N on its error delayed by delay_s (a whole number of sub-steps), integrated
// with RK4 on 40 sub-steps per sample (the input linear between samples):
//   y' = v, v' = (k N(e(t - delay_s)) - v) / T, e = u - y.
// The delayed error at a stage's half step is the mean of its two sub-step neighbours.
Eigen::VectorXd integrated_loop(const Eigen::VectorXd& u, double dt_s,
                                const std::function<double(double)>& n, double delay_s = 0.0) {
  constexpr int kSub = 40;
  const double h = dt_s / kSub;
  const auto lag = static_cast<std::ptrdiff_t>(std::lround(delay_s / h));
  std::vector<double> history;  // e at every sub-step so far
  double y = 0.0, v = 0.0;
  Eigen::VectorXd out(u.size());
  auto input = [&](Eigen::Index k, double t_frac) {
    return k + 1 < u.size() ? u(k) + t_frac * (u(k + 1) - u(k)) : u(k);
  };
  // e delayed, at sub-step j plus half a sub-step (half = 0.5) or not (0); e_now if no delay.
  auto delayed = [&](double e_now, double half, std::ptrdiff_t j) {
    if (lag == 0) return e_now;
    const auto at = [&](std::ptrdiff_t i) {
      return history[static_cast<std::size_t>(std::max<std::ptrdiff_t>(i, 0))];
    };
    return (1.0 - half) * at(j - lag) + half * at(j - lag + 1);
  };
  auto f = [&](double t_frac, Eigen::Index k, double half, std::ptrdiff_t j, double yy, double vv,
               double* dy, double* dv) {
    *dy = vv;
    *dv = (kLoopGain * n(delayed(input(k, t_frac) - yy, half, j)) - vv) / kLoopLagS;
  };
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    out(k) = y;
    for (int i = 0; i < kSub; ++i) {
      const auto j = static_cast<std::ptrdiff_t>(history.size());
      history.push_back(input(k, static_cast<double>(i) / kSub) - y);
      const double t0 = static_cast<double>(i) / kSub, th = 0.5 / kSub, t1 = 1.0 / kSub;
      double a1, b1, a2, b2, a3, b3, a4, b4;
      f(t0, k, 0.0, j, y, v, &a1, &b1);
      f(t0 + th, k, 0.5, j, y + 0.5 * h * a1, v + 0.5 * h * b1, &a2, &b2);
      f(t0 + th, k, 0.5, j, y + 0.5 * h * a2, v + 0.5 * h * b2, &a3, &b3);
      f(t0 + t1, k, 1.0, j, y + h * a3, v + h * b3, &a4, &b4);
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
  const Eigen::VectorXd y = close_error_loop(in.model, u, z0, in.model.dc_gain(), in.dt_s,
                                             [](std::span<const double> e) { return e.back(); });
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
  const Eigen::VectorXd y = close_error_loop(
      closed_loop(), u, z0, 1.0, dt_s, [&](std::span<const double> e) { return db(e.back()); });
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

// On a two-level input a governor's error deadband shortens every (equal) step alike, as a
// gain would: whichever is named, the other is named beside it as fitting about as well.
TEST(ErrorLoop, OnATwoLevelInputADeadbandAndAGainAreNamedTogether) {
  DiagnoseInput in = null_record(67);
  in.model = closed_loop();
  in.u = two_level(in.u.size(), 67);
  const Eigen::VectorXd e0 = in.u - model::simulate(in.model, in.u, in.dt_s);
  const double w = 0.4 * rms(e0);
  const Eigen::VectorXd y = integrated_loop(in.u, in.dt_s, [w](double e) {
    return e > w ? e - w : e < -w ? e + w : 0.0;
  });
  in.y = y + white(y.size(), 0.1 * rms(y), 19);
  const DiagnoseResult r = diagnose(in);
  ASSERT_TRUE(r.verdict == "deadband" || r.verdict == "gain_change") << r.explanation;
  ASSERT_GE(r.alternative_index, 0) << r.explanation;
  const std::string other = verdict_of(r.hypotheses[static_cast<std::size_t>(r.alternative_index)]);
  EXPECT_EQ(other, r.verdict == "deadband" ? "gain_change" : "deadband") << r.explanation;
  EXPECT_NE(r.explanation.find("does not tell the two apart"), std::string::npos) << r.explanation;
  EXPECT_NE(r.explanation.find("a test whose bias varies in amplitude"), std::string::npos)
      << r.explanation;
}

// A dead time inside the loop (a fuel transport delay) changes the loop's dynamics: the
// stepped loop with the dead time's form on the error against the integrated one.
TEST(ErrorLoop, ADeadTimeOnTheErrorMatchesTheIntegratedLoop) {
  const DiagnoseInput in = null_record(64);
  const double dt_s = in.dt_s, delay_s = 3.0 * dt_s;
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const auto identity = [](double e) { return e; };
  const Eigen::VectorXd reference = integrated_loop(u, dt_s, identity, delay_s);
  const Eigen::VectorXd z0 = model::simulate(closed_loop(), u, dt_s);
  const auto on_error = effect_model(Effect::kDeadTime).apply_on_error;
  const Eigen::VectorXd y = close_error_loop(
      closed_loop(), u, z0, 1.0, dt_s,
      [&](std::span<const double> e) { return on_error({delay_s}, e, 1.0, dt_s); });
  // Not a delay of the output: the loop's response changes shape.
  const Eigen::VectorXd shifted = model::simulate(
      model::TransferFunction{closed_loop().num, closed_loop().den, delay_s}, u, dt_s);
  ASSERT_GT(rms(reference - z0), 0.05 * rms(reference));
  EXPECT_GT(rms(shifted - reference), 0.1 * rms(reference - z0));
  EXPECT_LT(rms(y - reference), 0.02 * rms(reference - z0));
}

TEST(ErrorLoop, ADeadTimeInTheLoopIsFoundOnTheError) {
  DiagnoseInput in = null_record(65);
  in.model = closed_loop();
  const Eigen::VectorXd u = in.u.array() - in.u.mean();
  const double delay_s = 0.05;
  const Eigen::VectorXd y = integrated_loop(
      u, in.dt_s, [](double e) { return e; }, delay_s);
  in.y = y + white(y.size(), 0.1 * rms(y), 17);
  const DiagnoseResult r = diagnose(in);
  ASSERT_EQ(r.verdict, "dead_time") << r.explanation;
  const AppliedEffect& e = r.chosen()->effects.front();
  EXPECT_EQ(e.place, Place::kError) << r.explanation;
  EXPECT_NEAR(e.params[0], delay_s, 0.2 * delay_s) << r.explanation;
  EXPECT_NE(r.explanation.find("inside the governor's loop"), std::string::npos) << r.explanation;
  // The augmented model keeps the delay out of its transfer function and says where it acts.
  model::ModelFile base;
  base.tf = in.model;
  const model::ModelFile aug = augmented_model(r, base);
  EXPECT_EQ(aug.tf.delay_s, in.model.delay_s);
  EXPECT_EQ(aug.extra["augmentation"][0]["acts"], place_acts(Place::kError));
}

}  // namespace
}  // namespace rig::diagnose
