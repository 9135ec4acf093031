#include "rig/model/transfer_function.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>

namespace rig::model {
namespace {

TransferFunction make_tf(std::initializer_list<double> num, std::initializer_list<double> den,
                         double delay_s = 0.0) {
  TransferFunction tf;
  tf.num = Eigen::Map<const Eigen::VectorXd>(num.begin(), static_cast<Eigen::Index>(num.size()));
  tf.den = Eigen::Map<const Eigen::VectorXd>(den.begin(), static_cast<Eigen::Index>(den.size()));
  tf.delay_s = delay_s;
  return tf;
}

Eigen::VectorXd time_axis(Eigen::Index n, double dt) {
  return Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1) * dt);
}

TEST(TransferFunction, RampThroughFirstOrderIsExact) {
  // y = t - 1 + e^{-t} for u = t through 1/(s+1).
  const double dt = 0.1;
  const Eigen::VectorXd t = time_axis(200, dt);
  const Eigen::VectorXd y = simulate(make_tf({1.0}, {1.0, 1.0}), t, dt);
  for (Eigen::Index k = 0; k < t.size(); ++k)
    EXPECT_NEAR(y(k), t(k) - 1.0 + std::exp(-t(k)), 1e-11) << "k=" << k;
}

TEST(TransferFunction, FractionalDelayIsExact) {
  const double dt = 0.1, td = 0.237;  // 2.37 samples
  const Eigen::VectorXd t = time_axis(200, dt);
  const Eigen::VectorXd y = simulate(make_tf({1.0}, {1.0, 1.0}, td), t, dt);
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    const double s = t(k) - td;
    EXPECT_NEAR(y(k), s > 0 ? s - 1.0 + std::exp(-s) : 0.0, 1e-11) << "k=" << k;
  }
}

TEST(TransferFunction, DelayedStepThroughSecondOrderIsExact) {
  // 10/(s^2+2s+10): step response 1 - e^{-t}(cos 3t + sin(3t)/3), delayed by 5.5 samples.
  const double dt = 0.01, td = 0.055;
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(600);
  const Eigen::VectorXd y = simulate(make_tf({10.0}, {1.0, 2.0, 10.0}, td), u, dt);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double s = static_cast<double>(k) * dt - td;
    const double exact =
        s > 0 ? 1.0 - std::exp(-s) * (std::cos(3 * s) + std::sin(3 * s) / 3.0) : 0.0;
    EXPECT_NEAR(y(k), exact, 1e-10) << "k=" << k;
  }
}

TEST(TransferFunction, FractionalDelayOfKinkedInputMatchesFineReference) {
  // A random piecewise-linear input, delayed by integer and fractional sample counts, against
  // the same input upsampled 50x (exact knots) and simulated at the fine step.
  const Eigen::Index n = 300, up = 50;
  const double dt = 0.01;
  Eigen::VectorXd u(n);
  double s = 0.3;
  for (Eigen::Index i = 0; i < n; ++i) u(i) = s = std::fmod(s * 7.13 + 0.37, 2.0) - 1.0 + 0.5 * s;
  Eigen::VectorXd fine((n - 1) * up + 1);
  for (Eigen::Index i = 0; i + 1 < n; ++i)
    for (Eigen::Index k = 0; k < up; ++k)
      fine(i * up + k) = u(i) + (u(i + 1) - u(i)) * static_cast<double>(k) / up;
  fine(fine.size() - 1) = u(n - 1);
  for (double td : {0.06, 0.0637}) {
    const TransferFunction tf = make_tf({1.0}, {0.07, 0.19, 11.05}, td);
    const Eigen::VectorXd y = simulate(tf, u, dt), yf = simulate(tf, fine, dt / up);
    double err = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) err = std::max(err, std::abs(y(i) - yf(i * up)));
    EXPECT_LT(err, 1e-8 * y.cwiseAbs().maxCoeff() + 1e-12) << "td " << td;
  }
}

// The state's size picks the sample loop (fixed sizes up to 10, dynamic above): a cascade of
// two sixth-order sections (fixed) with a fractional delay on the first agrees with the
// twelfth-order product (dynamic), and each section with its own filtered derivatives.
TEST(TransferFunction, FixedAndDynamicSizedStepsAgree) {
  const double dt = 0.01, td = 0.0633;  // 6.33 samples
  // Three second-order sections each (w in rad/s), numerators set for unit static gain.
  const auto conv = [](const Eigen::VectorXd& p, const Eigen::VectorXd& q) {
    Eigen::VectorXd r = Eigen::VectorXd::Zero(p.size() + q.size() - 1);
    for (Eigen::Index i = 0; i < p.size(); ++i) r.segment(i, q.size()) += p(i) * q;
    return r;
  };
  const auto section = [](double w, double z) { return Eigen::Vector3d(1.0, 2.0 * z * w, w * w); };
  Eigen::VectorXd a = conv(conv(section(1.0, 0.3), section(2.0, 0.2)), section(3.5, 0.1));
  Eigen::VectorXd b = conv(conv(section(1.5, 0.5), section(2.5, 0.15)), section(5.0, 0.4));
  TransferFunction g1{Eigen::VectorXd::Constant(1, a(a.size() - 1)), a, td};
  TransferFunction g2{Eigen::VectorXd::Constant(1, b(b.size() - 1)), b, 0.0};
  TransferFunction g12{Eigen::VectorXd::Constant(1, a(a.size() - 1) * b(b.size() - 1)), conv(a, b),
                       td};
  Eigen::VectorXd u(5000);  // smooth: the series path's interpolation error stays small
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double t = static_cast<double>(k) * dt;
    u(k) = std::sin(0.7 * t) + 0.5 * std::sin(2.9 * t + 1.0);
  }
  const Eigen::VectorXd series = simulate(g2, simulate(g1, u, dt), dt);
  const Eigen::VectorXd whole = simulate(g12, u, dt);
  const double scale = series.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.1);
  // The series path re-interpolates its intermediate signal linearly: agreement to the
  // first-order hold's error of a smooth signal (1e-5 of its peak here), not to rounding.
  EXPECT_LT((series - whole).cwiseAbs().maxCoeff(), 1e-4 * scale);
  const Eigen::VectorXd via_columns =
      filtered_derivatives(g1.den, u, dt, td).rightCols(1) * g1.num(0);
  EXPECT_LT((via_columns - simulate(g1, u, dt)).cwiseAbs().maxCoeff(), 1e-12 * scale);
}

TEST(TransferFunction, FreeResponseBasisSpansInitialTransients) {
  // 1/(s+2): the single free response from x0 = 1 is e^{-2t}.
  const Eigen::MatrixXd b = free_response_basis(make_tf({1.0}, {1.0, 2.0}), 50, 0.1);
  ASSERT_EQ(b.cols(), 1);
  for (Eigen::Index k = 0; k < 50; ++k) EXPECT_NEAR(b(k, 0), std::exp(-0.2 * k), 1e-12);
  EXPECT_EQ(free_response_basis(make_tf({1.0}, {1.0, 2.0, 10.0}), 10, 0.1).cols(), 2);
}

TEST(TransferFunction, BiproperStepHasFeedthrough) {
  // (2s+1)/(s+1) = 2 - 1/(s+1): step response 1 + e^{-t}.
  const double dt = 0.05;
  const Eigen::VectorXd t = time_axis(100, dt);
  const Eigen::VectorXd y =
      simulate(make_tf({2.0, 1.0}, {1.0, 1.0}), Eigen::VectorXd::Ones(100), dt);
  for (Eigen::Index k = 0; k < t.size(); ++k) EXPECT_NEAR(y(k), 1.0 + std::exp(-t(k)), 1e-11);
}

TEST(TransferFunction, ResponseGainPolesAndProperness) {
  const TransferFunction tf = make_tf({2.0}, {1.0, 1.0}, 0.1);
  const std::complex<double> h = tf.response(1.0 / (2.0 * M_PI));  // omega = 1
  EXPECT_NEAR(std::abs(h), 2.0 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(std::arg(h), -M_PI / 4.0 - 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(tf.dc_gain(), 2.0);
  EXPECT_TRUE(tf.is_stable());
  EXPECT_TRUE(tf.is_proper());
  EXPECT_FALSE(make_tf({1.0}, {1.0, -0.5, 2.0}).is_stable());
  EXPECT_FALSE(make_tf({1.0, 0.0, 1.0}, {1.0, 1.0}).is_proper());
  const Eigen::VectorXcd p = make_tf({1.0}, {1.0, 2.0, 10.0}).poles();
  ASSERT_EQ(p.size(), 2);
  EXPECT_NEAR(p(0).real(), -1.0, 1e-12);
  EXPECT_NEAR(std::abs(p(0).imag()), 3.0, 1e-12);
  EXPECT_THROW(simulate(make_tf({1.0, 0.0, 1.0}, {1.0, 1.0}), Eigen::VectorXd::Ones(3), 0.1),
               std::invalid_argument);
}

TEST(TransferFunction, FitPercentIsNrmse) {
  const Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(50, -1.0, 3.0);
  EXPECT_DOUBLE_EQ(fit_percent(y, y), 100.0);
  EXPECT_NEAR(fit_percent(y, Eigen::VectorXd::Constant(50, y.mean())), 0.0, 1e-12);
  const Eigen::VectorXd half = y.mean() + 0.5 * (y.array() - y.mean());
  EXPECT_NEAR(fit_percent(y, half), 50.0, 1e-12);
}

}  // namespace
}  // namespace rig::model
