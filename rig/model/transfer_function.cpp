#include "rig/model/transfer_function.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>
#include <utility>
#include <vector>

namespace rig::model {
namespace {

Eigen::VectorXd trim_leading_zeros(const Eigen::VectorXd& p) {
  Eigen::Index first = 0;
  while (first + 1 < p.size() && p(first) == 0.0) ++first;
  return p.tail(p.size() - first);
}

std::complex<double> polyval(const Eigen::VectorXd& p, std::complex<double> s) {
  std::complex<double> acc = 0.0;
  for (Eigen::Index i = 0; i < p.size(); ++i) acc = acc * s + p(i);
  return acc;
}

Eigen::VectorXcd roots(const Eigen::VectorXd& p_in) {
  const Eigen::VectorXd p = trim_leading_zeros(p_in);
  const Eigen::Index n = p.size() - 1;
  if (n < 1) return {};
  // Companion matrix of the monic polynomial; its eigenvalues are the roots.
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index j = 0; j < n; ++j) c(0, j) = -p(j + 1) / p(0);
  for (Eigen::Index i = 1; i < n; ++i) c(i, i - 1) = 1.0;
  return Eigen::EigenSolver<Eigen::MatrixXd>(c, false).eigenvalues();
}

}  // namespace

FohStep foh_step(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double h) {
  const Eigen::Index n = a.rows();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 2, n + 2);
  m.topLeftCorner(n, n) = a * h;
  m.block(0, n, n, 1) = b * h;
  m(n, n + 1) = h;
  const Eigen::MatrixXd e = m.exp();
  return {e.topLeftCorner(n, n), e.block(0, n, n, 1), e.block(0, n + 1, n, 1)};
}

std::complex<double> TransferFunction::evaluate(std::complex<double> s) const {
  return polyval(num, s) / polyval(den, s) * std::exp(-s * delay_s);
}

std::complex<double> TransferFunction::response(double freq_hz) const {
  return evaluate(std::complex<double>(0.0, 2.0 * M_PI * freq_hz));
}

double TransferFunction::dc_gain() const {
  const double a0 = den(den.size() - 1);
  const double b0 = num(num.size() - 1);
  if (a0 == 0.0)
    return b0 >= 0 ? std::numeric_limits<double>::infinity()
                   : -std::numeric_limits<double>::infinity();
  return b0 / a0;
}

Eigen::VectorXcd TransferFunction::poles() const { return roots(den); }
Eigen::VectorXcd TransferFunction::zeros() const { return roots(num); }

bool TransferFunction::is_stable() const {
  const Eigen::VectorXcd p = poles();
  for (Eigen::Index i = 0; i < p.size(); ++i)
    if (!(p(i).real() < 0.0)) return false;
  return true;
}

int TransferFunction::order() const { return static_cast<int>(trim_leading_zeros(den).size()) - 1; }
int TransferFunction::numerator_order() const {
  return static_cast<int>(trim_leading_zeros(num).size()) - 1;
}
bool TransferFunction::is_proper() const { return numerator_order() <= order(); }

TransferFunction monic(const TransferFunction& tf) {
  TransferFunction out{trim_leading_zeros(tf.num), trim_leading_zeros(tf.den), tf.delay_s};
  const double an = out.den(0);
  out.num /= an;
  out.den /= an;
  return out;
}

namespace {

// One sample step of the state-variable filter as an affine map, x' = P x + G w, with
// w = (v0, slope1, v1, slope2): the input's value and slope before the delayed knot inside
// the step and after it (without a fractional delay the second pair is unused, G's columns
// 2-3 zero). The two sub-steps of a fractional delay are folded into one: P = phi2 phi1.
struct StepMap {
  Eigen::MatrixXd p;  // n x n
  Eigen::MatrixXd g;  // n x 4
};

StepMap step_map(const Eigen::MatrixXd& a, const Eigen::VectorXd& bin, double dt_s, double f) {
  StepMap m;
  const Eigen::Index n = a.rows();
  m.g = Eigen::MatrixXd::Zero(n, 4);
  if (f == 0.0) {
    const FohStep full = foh_step(a, bin, dt_s);
    m.p = full.phi;
    m.g.col(0) = full.ga, m.g.col(1) = full.gb;
    return m;
  }
  const FohStep s1 = foh_step(a, bin, f * dt_s), s2 = foh_step(a, bin, (1.0 - f) * dt_s);
  m.p = s2.phi * s1.phi;
  m.g.col(0) = s2.phi * s1.ga, m.g.col(1) = s2.phi * s1.gb;
  m.g.col(2) = s2.ga, m.g.col(3) = s2.gb;
  return m;
}

// The sample loop for a state of N (compile-time, or Eigen::Dynamic) entries: fixed sizes
// let the n x n product unroll, which is most of diagnose's time.
template <int N, class Input, class Sink>
void run_steps(const StepMap& m, const Eigen::VectorXd& a0_in, Eigen::Index samples, Input&& w_at,
               Sink&& sink) {
  using Vec = Eigen::Matrix<double, N, 1>;
  const Eigen::Matrix<double, N, N> p = m.p;
  const Eigen::Matrix<double, N, 4> g = m.g;
  const Vec a0 = a0_in;
  Vec x = Vec::Zero(m.p.rows());
  for (Eigen::Index k = 0; k < samples; ++k) {
    const Eigen::Vector4d w = w_at(k);
    sink(k, w(0) + a0.dot(x), x.data());  // p^n z = u - sum a_i p^i z
    // Coefficient-based products: at these sizes a call into Eigen's general kernel costs
    // more than the arithmetic (a fifth of diagnose's time on 600 s records).
    const Vec next = p.lazyProduct(x) + g.lazyProduct(w);
    x = next;
  }
}

// The orders diagnose and identify meet run at a fixed size (a tenth-order model with the
// effects of a pair added); larger ones at dynamic size.
inline constexpr int kMaxFixedOrder = 14;

template <int N, class Input, class Sink>
void run_sized(Eigen::Index n, const StepMap& m, const Eigen::VectorXd& a0, Eigen::Index samples,
               Input&& w_at, Sink&& sink) {
  if constexpr (N > kMaxFixedOrder) {
    run_steps<Eigen::Dynamic>(m, a0, samples, w_at, sink);
  } else if (n == N) {
    run_steps<N>(m, a0, samples, w_at, sink);
  } else {
    run_sized<N + 1>(n, m, a0, samples, w_at, sink);
  }
}

// The state-variable filter z = u(t - Td) / A(p) stepped sample by sample; at each sample k
// sink(k, top, x) receives p^n z (top) and the states x = [p^{n-1} z, ..., z] (n >= 1).
template <class Sink>
void step_filter(const Eigen::VectorXd& den_in, const Eigen::VectorXd& u, double dt_s,
                 double delay_s, Sink&& sink) {
  if (!(dt_s > 0.0)) throw std::invalid_argument("simulate: dt_s must be > 0");
  if (!(delay_s >= 0.0)) throw std::invalid_argument("simulate: delay_s must be >= 0");
  // An empty, all-zero or non-finite denominator (a degenerate estimate) has no filter.
  if (den_in.size() == 0 || !den_in.allFinite() || den_in.cwiseAbs().maxCoeff() == 0.0)
    throw std::invalid_argument(
        "filtered_derivatives: denominator must be non-empty, finite and not all zero");
  const Eigen::VectorXd trimmed = trim_leading_zeros(den_in);
  const Eigen::VectorXd den = trimmed / trimmed(0);
  const Eigen::Index n = den.size() - 1, N = u.size();
  // Delay Td = (d + f) dt: delayed input ud(t_k) = (1-f) u_{k-d} + f u_{k-d-1}.
  const double delay_samples = delay_s / dt_s;
  const Eigen::Index d = static_cast<Eigen::Index>(std::floor(delay_samples + 1e-12));
  double f = delay_samples - static_cast<double>(d);
  if (f < 1e-9) f = 0.0;
  // u(t) = 0 for t < 0 and jumps to u_0 at t = 0, so the delayed input is 0 before Td.
  auto u_at = [&](Eigen::Index j) { return (j >= 0 && j < N) ? u(j) : 0.0; };
  auto ud = [&](Eigen::Index k) {
    if (k - d < 0 || (f > 0.0 && k - d - 1 < 0)) return 0.0;
    return (1.0 - f) * u_at(k - d) + f * u_at(k - d - 1);
  };
  if (n == 0) {
    for (Eigen::Index k = 0; k < N; ++k) sink(k, ud(k), static_cast<const double*>(nullptr));
    return;
  }
  // w = (v0, slope1, v1, slope2) of step k (StepMap).
  const auto w_at = [&](Eigen::Index k) {
    const double v0 = ud(k);
    // Left limit at t_{k+1}: the delayed input is still 0 there when it starts at t_{k+1}.
    const double v2 = (f == 0.0 && k + 1 - d <= 0) ? 0.0 : ud(k + 1);
    if (f == 0.0) return Eigen::Vector4d(v0, (v2 - v0) / dt_s, 0.0, 0.0);
    // The delayed knot inside the step: left value (0 before the input starts), right value.
    const double v1l = k - d - 1 < 0 ? 0.0 : u_at(k - d), v1 = u_at(k - d);
    return Eigen::Vector4d(v0, (v1l - v0) / (f * dt_s), v1, (v2 - v1) / ((1.0 - f) * dt_s));
  };
  // Controllable canonical form: x = [p^{n-1} z, ..., z], z = u / A(p).
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  a.row(0) = -den.tail(n).transpose();
  for (Eigen::Index i = 1; i < n; ++i) a(i, i - 1) = 1.0;
  Eigen::VectorXd bin = Eigen::VectorXd::Zero(n);
  bin(0) = 1.0;
  const StepMap m = step_map(a, bin, dt_s, f);
  const Eigen::VectorXd a0 = a.row(0).transpose();
  run_sized<1>(n, m, a0, N, w_at, sink);
}

}  // namespace

Eigen::MatrixXd filtered_derivatives(const Eigen::VectorXd& den, const Eigen::VectorXd& u,
                                     double dt_s, double delay_s) {
  const Eigen::Index n = std::max<Eigen::Index>(trim_leading_zeros(den).size() - 1, 0);
  Eigen::MatrixXd out(u.size(), n + 1);
  step_filter(den, u, dt_s, delay_s, [&](Eigen::Index k, double top, const double* x) {
    out(k, 0) = top;
    for (Eigen::Index i = 0; i < n; ++i) out(k, i + 1) = x[i];
  });
  return out;
}

Eigen::MatrixXd free_response_basis(const TransferFunction& tf_in, Eigen::Index samples,
                                    double dt_s) {
  const TransferFunction tf = monic(tf_in);
  const Eigen::Index n = tf.den.size() - 1;
  Eigen::MatrixXd out(samples, n);
  if (n == 0) return out;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  b.tail(tf.num.size()) = tf.num;
  // y = sum_{i<n} (b_i - b_n a_i) p^i z for zero input, states x = [p^{n-1} z .. z].
  const Eigen::RowVectorXd c = (b.tail(n) - b(0) * tf.den.tail(n)).transpose();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  a.row(0) = -tf.den.tail(n).transpose();
  for (Eigen::Index i = 1; i < n; ++i) a(i, i - 1) = 1.0;
  const Eigen::MatrixXd phi = (a * dt_s).exp();
  Eigen::MatrixXd x = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index k = 0; k < samples; ++k) {
    out.row(k) = c * x;
    x = phi * x;
  }
  return out;
}

namespace {

// A monic denominator with a coefficient above this is stepped in a scaled time (below).
// The models identified here stay far below it (a tenth-order genset model reaches 1e12);
// a fourteenth-order one, a model closed in a loop with a transport delay, reaches 1e21,
// where the matrix exponential of its companion matrix loses every digit.
inline constexpr double kScaledTimeAbove = 1e15;

// The same system in the time t' = w0 t, w0 = |a_0|^(1/n) of the monic denominator (its
// roots' geometric mean): H'(s') = H(w0 s'), coefficients of s'^k times w0^(k - n), so that
// the companion matrix is of order one; stepped with dt' = w0 dt and Td' = w0 Td, it maps
// the same samples to the same samples.
TransferFunction scaled_time(const TransferFunction& tf, double& w0) {
  const Eigen::Index n = tf.den.size() - 1;
  w0 = std::pow(std::abs(tf.den(n)), 1.0 / static_cast<double>(n));
  TransferFunction out = tf;
  for (Eigen::Index j = 0; j <= n; ++j) out.den(j) *= std::pow(w0, -static_cast<double>(j));
  const Eigen::Index m = tf.num.size() - 1;
  for (Eigen::Index j = 0; j <= m; ++j) out.num(j) *= std::pow(w0, static_cast<double>(m - j - n));
  out.delay_s = tf.delay_s * w0;
  return out;
}

}  // namespace

Eigen::VectorXd simulate(const TransferFunction& tf_in, const Eigen::VectorXd& u, double dt_s) {
  if (tf_in.den.size() == 0 || tf_in.num.size() == 0 || tf_in.den.cwiseAbs().maxCoeff() == 0)
    throw std::invalid_argument("simulate: empty numerator or zero denominator");
  if (!tf_in.is_proper()) throw std::invalid_argument("simulate: transfer function is improper");
  const TransferFunction tf = monic(tf_in);
  const Eigen::Index n = tf.den.size() - 1;
  if (n > 0 && tf.den.cwiseAbs().maxCoeff() > kScaledTimeAbove && tf.den(n) != 0.0 && dt_s > 0.0) {
    double w0 = 1.0;
    const TransferFunction scaled = scaled_time(tf, w0);
    if (scaled.den.cwiseAbs().maxCoeff() < tf.den.cwiseAbs().maxCoeff())
      return simulate(scaled, u, dt_s * w0);
  }
  // y = B(p) z with z = u(t - Td) / A(p): numerator padded to n+1 terms.
  std::vector<double> b(static_cast<size_t>(n + 1), 0.0);
  for (Eigen::Index i = 0; i < tf.num.size(); ++i)
    b[static_cast<size_t>(n + 1 - tf.num.size() + i)] = tf.num(i);
  // y_k = b_0 p^n z + sum b_{i+1} x_i, summed as the filter steps (no n+1 columns stored).
  Eigen::VectorXd y(u.size());
  step_filter(tf.den, u, dt_s, tf.delay_s, [&](Eigen::Index k, double top, const double* x) {
    double acc = b[0] * top;
    for (Eigen::Index i = 0; i < n; ++i) acc += b[static_cast<size_t>(i + 1)] * x[i];
    y(k) = acc;
  });
  return y;
}

namespace {

// [begin, end) of record i of `starts` within n samples.
std::pair<Eigen::Index, Eigen::Index> record_span(const RecordStarts& starts, std::size_t i,
                                                  Eigen::Index n) {
  const Eigen::Index end = i + 1 < starts.size() ? starts[i + 1] : n;
  if (starts[i] < 0 || end > n || end <= starts[i])
    throw std::invalid_argument("record starts must be ascending within the signal");
  return {starts[i], end};
}

}  // namespace

Eigen::VectorXd simulate(const TransferFunction& tf, const Eigen::VectorXd& u, double dt_s,
                         const RecordStarts& starts) {
  if (starts.size() < 2) return simulate(tf, u, dt_s);
  Eigen::VectorXd out(u.size());
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const auto [b, e] = record_span(starts, i, u.size());
    out.segment(b, e - b) = simulate(tf, u.segment(b, e - b), dt_s);
  }
  return out;
}

Eigen::MatrixXd filtered_derivatives(const Eigen::VectorXd& den, const Eigen::VectorXd& u,
                                     double dt_s, double delay_s, const RecordStarts& starts) {
  if (starts.size() < 2) return filtered_derivatives(den, u, dt_s, delay_s);
  Eigen::MatrixXd out;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const auto [b, e] = record_span(starts, i, u.size());
    const Eigen::MatrixXd part = filtered_derivatives(den, u.segment(b, e - b), dt_s, delay_s);
    if (i == 0) out.resize(u.size(), part.cols());
    out.middleRows(b, e - b) = part;
  }
  return out;
}

double fit_percent(const Eigen::VectorXd& y, const Eigen::VectorXd& yhat) {
  if (y.size() != yhat.size() || y.size() == 0)
    throw std::invalid_argument("fit_percent: y and yhat must be equally long and non-empty");
  const double den = (y.array() - y.mean()).matrix().norm();
  if (den == 0.0) return std::numeric_limits<double>::quiet_NaN();
  return 100.0 * (1.0 - (y - yhat).norm() / den);
}

}  // namespace rig::model
