// Each bad case is built synthetically from a known plant and must raise its flag; the
// clean record must raise none. Seeds are fixed and printed.
#include "rig/ident/quality.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "rig/model/transfer_function.hpp"
#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/excitation.hpp"

namespace rig::ident {
namespace {

constexpr double kDt = 0.01;
constexpr Eigen::Index kN = 8192;
constexpr std::uint64_t kSeed = 20261121;

// 2nd order + delay: K = 1, fn = 2 Hz, zeta = 0.3, Td = 0.1 s.
model::TransferFunction plant(double zeta = 0.3) {
  const double wn = 2 * M_PI * 2.0;
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, wn * wn);
  tf.den = (Eigen::VectorXd(3) << 1.0, 2 * zeta * wn, wn * wn).finished();
  tf.delay_s = 0.1;
  return tf;
}

Eigen::VectorXd excitation() {
  signal::GaussianOptions g;
  g.n = kN;
  g.dt_s = kDt;
  g.bandwidth_hz = 5.0;
  g.seed = kSeed;
  return signal::gaussian_excitation(g);
}

Eigen::VectorXd noisy(const Eigen::VectorXd& y, double rel, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> d(0.0, rel * std::sqrt((y.array() - y.mean()).square().mean()));
  Eigen::VectorXd out = y;
  for (Eigen::Index i = 0; i < y.size(); ++i) out[i] += d(rng);
  return out;
}

QualityOptions options() {
  QualityOptions o;
  o.correlator.lags = 256;
  return o;
}

std::string describe(const QualityReport& rep) {
  std::string s = "seed " + std::to_string(kSeed) + "; flags:";
  for (const auto& f : rep.flags)
    s += " [" + f.name + " " + to_string(f.severity) + ": " + f.message + "]";
  s += " figures:";
  for (const auto& [k, v] : rep.figures) s += " " + k + "=" + std::to_string(v);
  return s;
}

TEST(Quality, CleanRecordRaisesNoFlag) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = noisy(simulate(plant(), u, kDt), 0.2, kSeed + 1);
  const QualityReport rep = check_quality(u, y, kDt, options());
  std::cout << describe(rep) << "\n";  // the margins to every threshold
  EXPECT_TRUE(rep.flags.empty()) << describe(rep);
  EXPECT_FALSE(rep.has_fatal());
}

TEST(Quality, CleanUnderdampedPlantAndPrbsInputRaiseNoFlag) {
  signal::PrbsOptions p;
  p.n = kN;
  p.clock_divider = 3;
  p.seed = kSeed;
  const Eigen::VectorXd u = signal::prbs_excitation(p);
  const Eigen::VectorXd y = noisy(simulate(plant(0.1), u, kDt), 0.2, kSeed + 2);
  const QualityReport rep = check_quality(u, y, kDt, options());
  std::cout << describe(rep) << "\n";  // the margins to every threshold
  EXPECT_TRUE(rep.flags.empty()) << describe(rep);
}

TEST(Quality, NoResponseWhenOutputIsUnrelatedNoise) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = noisy(Eigen::VectorXd::Zero(kN), 1.0, kSeed + 3).array() +
                            noisy(simulate(plant(), excitation().reverse(), kDt), 0.0, 1).array();
  const QualityReport rep = check_quality(u, y, kDt, options());
  ASSERT_NE(rep.find("no_response"), nullptr) << describe(rep);
  EXPECT_EQ(rep.find("no_response")->severity, Severity::kFatal);
}

TEST(Quality, SwappedChannelsAreAcausal) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = noisy(simulate(plant(), u, kDt), 0.1, kSeed + 4);
  const QualityReport rep = check_quality(y, u, kDt, options());
  ASSERT_NE(rep.find("acausal"), nullptr) << describe(rep);
  EXPECT_EQ(rep.find("acausal")->severity, Severity::kFatal);
}

TEST(Quality, OutputTimeStampsAheadOfInputAreAcausal) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = noisy(simulate(plant(0.7), u, kDt), 0.1, kSeed + 5);
  const Eigen::Index skew = 60;  // output recorded 0.6 s early: net advance 0.5 s
  const Eigen::VectorXd u_late = u.head(kN - skew);
  const Eigen::VectorXd y_early = y.tail(kN - skew);
  const QualityReport rep = check_quality(u_late, y_early, kDt, options());
  ASSERT_NE(rep.find("acausal"), nullptr) << describe(rep);
}

TEST(Quality, SingleSineIsNotPersistentlyExcitingForSecondOrderPlusDelay) {
  Eigen::VectorXd u(kN);
  for (Eigen::Index i = 0; i < kN; ++i) u[i] = std::sin(2 * M_PI * 1.3 * kDt * double(i));
  const Eigen::VectorXd y = noisy(simulate(plant(), u, kDt), 0.05, kSeed + 6);
  const QualityReport rep = check_quality(u, y, kDt, options());
  ASSERT_NE(rep.find("not_persistently_exciting"), nullptr) << describe(rep);
  QualityOptions first_order = options();
  first_order.order = {1, 0};
  first_order.delay_estimated = false;
  EXPECT_EQ(check_quality(u, y, kDt, first_order).find("not_persistently_exciting"), nullptr)
      << "one sine determines the two parameters of b0 / (s + a0)";
}

TEST(Quality, ClippedOutputAndInputAreFlagged) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = noisy(simulate(plant(), u, kDt), 0.05, kSeed + 7);
  const double top = 0.5 * y.maxCoeff();
  const Eigen::VectorXd y_clipped = y.cwiseMin(top);
  const QualityReport rep = check_quality(u, y_clipped, kDt, options());
  ASSERT_NE(rep.find("output_clipped"), nullptr) << describe(rep);
  EXPECT_EQ(rep.find("input_clipped"), nullptr);

  const Eigen::VectorXd u_clipped = u.cwiseMax(-1.0).cwiseMin(1.0);  // +-1 sigma: 32 % clipped
  const QualityReport rep_u =
      check_quality(u_clipped, simulate(plant(), u_clipped, kDt), kDt, options());
  ASSERT_NE(rep_u.find("input_clipped"), nullptr) << describe(rep_u);
  EXPECT_EQ(rep_u.find("input_clipped")->severity, Severity::kFatal);
}

TEST(Quality, SlowPlantLeavesCrossCorrelationUndecayed) {
  const Eigen::VectorXd u = excitation();
  model::TransferFunction slow;  // time constant 3 s against a 1.5 s window
  slow.num = Eigen::VectorXd::Constant(1, 1.0);
  slow.den = (Eigen::VectorXd(2) << 3.0, 1.0).finished();
  const Eigen::VectorXd y = noisy(simulate(slow, u, kDt), 0.05, kSeed + 8);
  const QualityReport rep = check_quality(u, y, kDt, options());
  ASSERT_NE(rep.find("undecayed"), nullptr) << describe(rep);
}

TEST(Quality, OutputCoupledAloneSagsAsOppositeSignTail) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = simulate(plant(0.7), u, kDt);
  const Eigen::VectorXd y_ac = noisy(signal::ac_couple(y, kDt, 0.3), 0.05, kSeed + 9);
  QualityOptions o = options();
  o.coupling_rc_s = 0.3;
  const QualityReport rep = check_quality(u, y_ac, kDt, o);
  ASSERT_NE(rep.find("coupling_mismatch"), nullptr) << describe(rep);
  // With the matched network on the input too, H is recovered exactly: no flag.
  const Eigen::VectorXd u_ac = signal::ac_couple(u, kDt, 0.3);
  const QualityReport matched = check_quality(u_ac, y_ac, kDt, o);
  EXPECT_EQ(matched.find("coupling_mismatch"), nullptr) << describe(matched);
}

TEST(Quality, CoupledChannelsWithDifferentTimeConstantsAreFatal) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = simulate(plant(), u, kDt);
  EXPECT_NEAR(fitted_coupling_rc_s(u, signal::ac_couple(u, kDt, 1.59), kDt), 1.59, 0.01 * 1.59);
  QualityOptions o = options();
  o.coupling_rc_s = 1.59;
  o.coupled_pairs = {{"u_ac", u, signal::ac_couple(u, kDt, 1.59)},
                     {"y_ac", y, signal::ac_couple(y, kDt, 0.8)}};
  const QualityReport rep = check_quality(u, y, kDt, o);
  ASSERT_NE(rep.find("coupling_mismatch"), nullptr) << describe(rep);
  EXPECT_EQ(rep.find("coupling_mismatch")->severity, Severity::kFatal);
  o.coupled_pairs[1].coupled = signal::ac_couple(y, kDt, 1.59);
  EXPECT_EQ(check_quality(u, y, kDt, o).find("coupling_mismatch"), nullptr);
}

TEST(Quality, JitteredTimeStampsAreFlagged) {
  const Eigen::VectorXd u = excitation();
  const Eigen::VectorXd y = simulate(plant(), u, kDt);
  QualityOptions o = options();
  o.jitter_max_s = 0.3 * kDt;
  const QualityReport rep = check_quality(u, y, kDt, o);
  ASSERT_NE(rep.find("non_uniform_sampling"), nullptr);
  EXPECT_EQ(rep.find("non_uniform_sampling")->severity, Severity::kFatal);
  o.jitter_max_s = 0.05 * kDt;
  EXPECT_EQ(check_quality(u, y, kDt, o).find("non_uniform_sampling")->severity, Severity::kWarning);
}

TEST(Quality, TooShortRecordIsRejected) {
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(100);
  EXPECT_THROW(check_quality(u, u, kDt, options()), std::invalid_argument);
}

}  // namespace
}  // namespace rig::ident
