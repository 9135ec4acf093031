#include "rig/diagnose/error_loop.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace rig::diagnose {
namespace {

// When the dead time is under a sample, d_k acts on the output at the same sample through
// the hold's slope: the scalar loop d_k = e_k - N(e_k) is solved by this many passes (the
// slope's share is O(dt / T), so each pass shrinks the error by as much). A dead time on the
// error of under a sample is solved the same way.
constexpr int kSameSamplePasses = 3;

}  // namespace

namespace {

// What the sample loop needs of the linear part: the hold's step of the controllable form
// (x = [p^{n-1} w .. w], w = ud / A(p), as model::filtered_derivatives) and the output's rows.
struct LoopStep {
  Eigen::MatrixXd phi;
  Eigen::VectorXd ga, gb, top_row, out_row;
  double b0 = 0.0;
  Eigen::Index whole = 0;  // the dead time's whole samples
  double frac = 0.0;       // and its fraction of one
};

// The sample loop for a state of N entries (compile-time, or Eigen::Dynamic): fixed sizes let
// the n x n product unroll, as model::simulate's does. The correction G d at sample k is
// affine in the delayed d there (only the hold's slope into it depends on it), so the state's
// part that does not is stepped once per sample and each pass solving d_k costs O(1).
template <int N>
Eigen::VectorXd run_error_loop(const LoopStep& m, const Eigen::VectorXd& u,
                               const Eigen::VectorXd& z0, double g0, double dt_s,
                               const std::function<double(std::span<const double>)>& on_error,
                               const LoopFeedback* feedback) {
  using Vec = Eigen::Matrix<double, N, 1>;
  const Eigen::Matrix<double, N, N> phi = m.phi;
  const Vec ga = m.ga, gb = m.gb, top_row = m.top_row, out_row = m.out_row;
  const double top_gb = top_row.dot(gb), out_gb = out_row.dot(gb);
  const Eigen::Index samples = u.size(), whole = m.whole;
  const double frac = m.frac;
  std::vector<double> d(static_cast<std::size_t>(samples), 0.0), es(d.size(), 0.0);
  auto d_at = [&](Eigen::Index j) { return j >= 0 ? d[static_cast<std::size_t>(j)] : 0.0; };
  // The delayed d (0 before it starts, as model::filtered_derivatives has it).
  auto ud = [&](Eigen::Index k) {
    if (k - whole < 0 || (frac > 0.0 && k - whole - 1 < 0)) return 0.0;
    return (1.0 - frac) * d_at(k - whole) + frac * d_at(k - whole - 1);
  };
  Vec x = Vec::Zero(m.phi.rows()), base = x;
  Eigen::VectorXd y(samples);
  std::optional<FeedbackFilter> seen;
  if (feedback) seen.emplace(*feedback, dt_s);
  double ud_prev = 0.0;
  for (Eigen::Index k = 0; k < samples; ++k) {
    // x = base + gb v_end / dt: the part of the step that does not depend on d_k.
    if (k > 0) base = phi.lazyProduct(x) + ga * ud_prev - gb * (ud_prev / dt_s);
    const double top_base = top_row.dot(base), out_base = out_row.dot(base);
    // With a whole-sample dead time the delayed d jumps at it: the step into it holds 0.
    const auto v_end = [&](double v) { return (frac == 0.0 && k - whole <= 0) ? 0.0 : v; };
    const auto correction = [&]() {
      const double v = ud(k);
      if (k == 0) return m.b0 * v;  // the state starts at zero
      const double r = v_end(v) / dt_s;
      return m.b0 * (v + top_base + top_gb * r) + out_base + out_gb * r;
    };
    const int passes = whole == 0 ? kSameSamplePasses : 1;
    double c = 0.0;
    const auto i = static_cast<std::size_t>(k);
    d[i] = d_at(k - 1);
    for (int pass = 0; pass < passes; ++pass) {
      c = correction();
      es[i] = seen ? u(k) - seen->at((z0(k) - c) / g0) : u(k) - (z0(k) - c) / g0;
      d[i] = es[i] - on_error(std::span<const double>(es.data(), i + 1));
    }
    if (whole == 0) c = correction();
    y(k) = z0(k) - c;
    if (seen) seen->advance(y(k) / g0);
    if (k > 0) x = base + gb * (v_end(ud(k)) / dt_s);
    ud_prev = ud(k);
  }
  return y;
}

inline constexpr int kMaxFixedOrder = 14;  // as model::simulate's

template <int N>
Eigen::VectorXd run_sized(const LoopStep& m, const Eigen::VectorXd& u, const Eigen::VectorXd& z0,
                          double g0, double dt_s,
                          const std::function<double(std::span<const double>)>& on_error,
                          const LoopFeedback* feedback) {
  if constexpr (N > kMaxFixedOrder) {
    return run_error_loop<Eigen::Dynamic>(m, u, z0, g0, dt_s, on_error, feedback);
  } else {
    if (m.phi.rows() == N) return run_error_loop<N>(m, u, z0, g0, dt_s, on_error, feedback);
    return run_sized<N + 1>(m, u, z0, g0, dt_s, on_error, feedback);
  }
}

}  // namespace

Eigen::VectorXd close_error_loop(const model::TransferFunction& tf_in, const Eigen::VectorXd& u,
                                 const Eigen::VectorXd& z0, double g0, double dt_s,
                                 const std::function<double(std::span<const double>)>& on_error,
                                 const LoopFeedback* feedback) {
  const model::TransferFunction tf = model::monic(tf_in);
  const Eigen::Index n = tf.den.size() - 1;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  b.tail(tf.num.size()) = tf.num;
  LoopStep m;
  const double delay_samples = tf.delay_s / dt_s;
  m.whole = static_cast<Eigen::Index>(std::floor(delay_samples + 1e-12));
  m.frac = delay_samples - static_cast<double>(m.whole);
  if (m.frac < 1e-9) m.frac = 0.0;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  if (n > 0) a.row(0) = -tf.den.tail(n).transpose();
  for (Eigen::Index i = 1; i < n; ++i) a(i, i - 1) = 1.0;
  Eigen::VectorXd bin = Eigen::VectorXd::Zero(n);
  if (n > 0) bin(0) = 1.0;
  const model::FohStep hold = n > 0 ? model::foh_step(a, bin, dt_s) : model::FohStep{};
  m.phi = n > 0 ? hold.phi : Eigen::MatrixXd(0, 0);
  m.ga = n > 0 ? hold.ga : Eigen::VectorXd(0);
  m.gb = n > 0 ? hold.gb : Eigen::VectorXd(0);
  m.top_row = n > 0 ? Eigen::VectorXd(a.row(0).transpose()) : Eigen::VectorXd(0);
  m.out_row = b.tail(n);
  m.b0 = b(0);
  return run_sized<0>(m, u, z0, g0, dt_s, on_error, feedback);
}

namespace {

// The PI loop's sums and the nonlinearity's state after one sample.
struct PiState {
  double sum_e = 0.0;     // sum of e_j
  double sum_d = 0.0;     // sum of d_j
  double filtered = 0.0;  // the PI's output through the filter, f_k
  double lost = 0.0;      // (a_k - N(a_k)) / k
  StepState step;
};

}  // namespace

double pi_filter_pole(double filter_lag_s, double dt_s) {
  return std::exp(-dt_s / std::max(filter_lag_s, 1e-300));
}

std::function<double(std::span<const double>)> pi_loop_on_error(Stepper step, double k,
                                                                const PiGovernor& gov,
                                                                double dt_s) {
  const double r = dt_s / gov.integral_time_s, p = pi_filter_pole(gov.filter_lag_s, dt_s);
  return [step = std::move(step), k, r, p, done = PiState{}, trial = PiState{},
          at = std::size_t{0}](std::span<const double> e) mutable {
    const std::size_t i = e.size() - 1;
    if (i != at) done = trial, at = i;  // a new sample: the last one's trial stands
    trial = done;
    const double ek = e.back();
    trial.sum_e += ek;
    trial.filtered = p * done.filtered + (1.0 - p) * (ek + r * trial.sum_e);
    const double a = k * trial.filtered;
    trial.lost = (a - step(trial.step, a)) / k;
    // The filter's input that gives `lost` at its output, then the PI's: d + r (sum_d + d).
    const double s = (trial.lost - p * done.lost) / (1.0 - p);
    const double d = (s - r * done.sum_d) / (1.0 + r);
    trial.sum_d += d;
    return ek - d;
  };
}

}  // namespace rig::diagnose
