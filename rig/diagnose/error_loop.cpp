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

Eigen::VectorXd close_error_loop(const model::TransferFunction& tf_in, const Eigen::VectorXd& u,
                                 const Eigen::VectorXd& z0, double g0, double dt_s,
                                 const std::function<double(std::span<const double>)>& on_error,
                                 const LoopFeedback* feedback) {
  const model::TransferFunction tf = model::monic(tf_in);
  const Eigen::Index n = tf.den.size() - 1, samples = u.size();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  b.tail(tf.num.size()) = tf.num;
  const double delay_samples = tf.delay_s / dt_s;
  const auto whole = static_cast<Eigen::Index>(std::floor(delay_samples + 1e-12));
  double frac = delay_samples - static_cast<double>(whole);
  if (frac < 1e-9) frac = 0.0;
  // Controllable form as model::filtered_derivatives: x = [p^{n-1} w .. w], w = ud / A(p).
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  if (n > 0) a.row(0) = -tf.den.tail(n).transpose();
  for (Eigen::Index i = 1; i < n; ++i) a(i, i - 1) = 1.0;
  Eigen::VectorXd bin = Eigen::VectorXd::Zero(n);
  if (n > 0) bin(0) = 1.0;
  const model::FohStep hold = n > 0 ? model::foh_step(a, bin, dt_s) : model::FohStep{};
  // The step as plain arrays (row-major phi): the state is small, and a general
  // matrix-vector product per sample costs more than the arithmetic.
  const auto nn = static_cast<std::size_t>(n);
  std::vector<double> phi(nn * nn), ga(nn), gb(nn), top_row(nn), out_row(nn);
  for (std::size_t i = 0; i < nn; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    for (std::size_t j = 0; j < nn; ++j)
      phi[i * nn + j] = hold.phi(ii, static_cast<Eigen::Index>(j));
    ga[i] = hold.ga(ii);
    gb[i] = hold.gb(ii);
    top_row[i] = a(0, ii);
    out_row[i] = b(ii + 1);
  }
  std::vector<double> d(static_cast<std::size_t>(samples), 0.0), es(d.size(), 0.0);
  auto d_at = [&](Eigen::Index j) { return j >= 0 ? d[static_cast<std::size_t>(j)] : 0.0; };
  // The delayed d (0 before it starts, as model::filtered_derivatives has it).
  auto ud = [&](Eigen::Index k) {
    if (k - whole < 0 || (frac > 0.0 && k - whole - 1 < 0)) return 0.0;
    return (1.0 - frac) * d_at(k - whole) + frac * d_at(k - whole - 1);
  };
  std::vector<double> x(nn, 0.0), x_prev(nn, 0.0);
  Eigen::VectorXd y(samples);
  std::optional<FeedbackFilter> seen;
  if (feedback) seen.emplace(*feedback, dt_s);
  double ud_prev = 0.0;
  for (Eigen::Index k = 0; k < samples; ++k) {
    // The state at k and the correction G d there, for the d_k guessed so far.
    auto correction = [&]() {
      const double v = ud(k);
      // With a whole-sample dead time the delayed d jumps at it: the step into it holds 0.
      const double v_end = (frac == 0.0 && k - whole <= 0) ? 0.0 : v;
      if (k > 0) {
        const double slope = (v_end - ud_prev) / dt_s;
        for (std::size_t i = 0; i < nn; ++i) {
          double s = ga[i] * ud_prev + gb[i] * slope;
          const double* row = &phi[i * nn];
          for (std::size_t j = 0; j < nn; ++j) s += row[j] * x_prev[j];
          x[i] = s;
        }
      }
      double top = v, out = 0.0;
      for (std::size_t i = 0; i < nn; ++i) top += top_row[i] * x[i], out += out_row[i] * x[i];
      return b(0) * top + out;
    };
    const int passes = whole == 0 ? kSameSamplePasses : 1;
    double c = 0.0;
    d[static_cast<std::size_t>(k)] = d_at(k - 1);
    for (int pass = 0; pass < passes; ++pass) {
      c = correction();
      const auto i = static_cast<std::size_t>(k);
      es[i] = seen ? u(k) - seen->at((z0(k) - c) / g0) : u(k) - (z0(k) - c) / g0;
      d[i] = es[i] - on_error(std::span<const double>(es.data(), i + 1));
    }
    if (whole == 0) c = correction();
    y(k) = z0(k) - c;
    if (seen) seen->advance(y(k) / g0);
    x_prev = x;
    ud_prev = ud(k);
  }
  return y;
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
