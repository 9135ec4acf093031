#include "rig/diagnose/blocks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

namespace rig::diagnose {

Eigen::VectorXd deadband(const Eigen::VectorXd& u, double w) {
  return u.unaryExpr([w](double x) { return x > w ? x - w : (x < -w ? x + w : 0.0); });
}

Eigen::VectorXd backlash(const Eigen::VectorXd& u, double b) {
  Eigen::VectorXd v(u.size());
  double prev = u.size() > 0 ? u(0) : 0.0;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    prev = std::min(std::max(prev, u(k) - b), u(k) + b);
    v(k) = prev;
  }
  return v;
}

double bouc_wen_step(double z, double du, double w, double r) {
  const double beta = 1.0 / (w * (1.0 + r)), gamma = r * beta;
  z += du - beta * std::abs(du) * z - gamma * du * std::abs(z);
  return std::clamp(z, -w, w);  // an increment larger than w would overshoot the envelope
}

Eigen::VectorXd bouc_wen(const Eigen::VectorXd& u, double w, double r) {
  Eigen::VectorXd v(u.size());
  double z = 0.0;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    z = bouc_wen_step(z, k > 0 ? u(k) - u(k - 1) : 0.0, w, r);
    v(k) = u(k) - z;
  }
  return v;
}

Eigen::VectorXd saturate(const Eigen::VectorXd& u, double lower, double upper) {
  return u.cwiseMax(lower).cwiseMin(upper);
}

Eigen::VectorXd rate_limit(const Eigen::VectorXd& u, double rate_per_s, double dt_s) {
  Eigen::VectorXd v(u.size());
  const double step = rate_per_s * dt_s;
  double prev = u.size() > 0 ? u(0) : 0.0;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    prev += std::clamp(u(k) - prev, -step, step);
    v(k) = prev;
  }
  return v;
}

double in_loop_recovery(double recovery_s, double dt_s) {
  return std::min(1.0, dt_s / std::max(recovery_s, 1e-300));
}

namespace {

// One step of the integrating loop: the input's increment plus the recovery of the lost
// position, (u_{k-1} - v_{k-1}) dt/T, at most all of it.
template <class Limit>
Eigen::VectorXd in_loop(const Eigen::VectorXd& u, double recovery_s, double dt_s, Limit limit) {
  Eigen::VectorXd v(u.size());
  if (u.size() == 0) return v;
  const double a = in_loop_recovery(recovery_s, dt_s);
  v(0) = limit(u(0), 0.0);
  for (Eigen::Index k = 1; k < u.size(); ++k)
    v(k) = limit(v(k - 1), u(k) - u(k - 1) + a * (u(k - 1) - v(k - 1)));
  return v;
}

}  // namespace

Eigen::VectorXd rate_limit_in_loop(const Eigen::VectorXd& u, double rate_per_s, double recovery_s,
                                   double dt_s) {
  const double step = rate_per_s * dt_s;
  return in_loop(u, recovery_s, dt_s,
                 [step](double prev, double inc) { return prev + std::clamp(inc, -step, step); });
}

Eigen::VectorXd saturate_in_loop(const Eigen::VectorXd& u, double lower, double upper,
                                 double recovery_s, double dt_s) {
  return in_loop(u, recovery_s, dt_s, [lower, upper](double prev, double inc) {
    return std::clamp(prev + inc, lower, std::max(lower, upper));
  });
}

Eigen::VectorXd polynomial(const Eigen::VectorXd& u, double c2, double c3, double sigma) {
  const double s = std::max(sigma, 1e-300);
  return u.unaryExpr([=](double x) { return x + c2 * x * x / s + c3 * x * x * x / (s * s); });
}

Eigen::VectorXd poly_multiply(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(a.size() + b.size() - 1);
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    for (Eigen::Index j = 0; j < b.size(); ++j) c(i + j) += a(i) * b(j);
  }
  return c;
}

Eigen::VectorXd poly_from_roots(const Eigen::VectorXcd& roots) {
  Eigen::VectorXcd c = Eigen::VectorXcd::Ones(1);
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    Eigen::VectorXcd next = Eigen::VectorXcd::Zero(c.size() + 1);
    next.head(c.size()) = c;
    next.tail(c.size()) -= roots(i) * c;
    c = next;
  }
  return c.real();
}

namespace {

// Delayed input with the same linear interpolation as model::simulate (delay d + f samples).
Eigen::VectorXd delayed(const Eigen::VectorXd& u, double delay_s, double dt_s) {
  const double ds = delay_s / dt_s;
  const Eigen::Index d = static_cast<Eigen::Index>(std::floor(ds + 1e-12));
  const double f = ds - static_cast<double>(d) < 1e-9 ? 0.0 : ds - static_cast<double>(d);
  const Eigen::Index n = u.size();
  auto at = [&](Eigen::Index j) { return (j >= 0 && j < n) ? u(j) : 0.0; };
  Eigen::VectorXd out(n);
  for (Eigen::Index k = 0; k < n; ++k) out(k) = (1.0 - f) * at(k - d) + f * at(k - d - 1);
  return out;
}

// One sample step of the loop closed through an output feedback: its state map (row-major
// phi), input column, output row and direct term.
struct FeedbackStep {
  const Eigen::MatrixXd& phi;
  const Eigen::VectorXd& gamma;
  const Eigen::RowVectorXd& c;
  double d0, dt_s;
};

// The sample loop on plain arrays of N states (compile-time, so that the small products
// unroll; kDynamicStates: run-time): a general matrix-vector product per sample costs more
// than the arithmetic of a small state. The sums run in the same order at either size.
inline constexpr int kDynamicStates = 0;
inline constexpr int kMaxFixedStates = 14;

template <int N>
void run_feedback(const FeedbackStep& s, const Eigen::VectorXd& ud, const OutputFeedback& feedback,
                  Eigen::VectorXd& out) {
  const auto nn = static_cast<std::size_t>(N == kDynamicStates ? s.phi.rows() : N);
  using Array = std::conditional_t<N == kDynamicStates, std::vector<double>,
                                   std::array<double, static_cast<std::size_t>(N)>>;
  using Square = std::conditional_t<N == kDynamicStates, std::vector<double>,
                                    std::array<double, static_cast<std::size_t>(N * N)>>;
  Array g{}, cr{}, x{}, next{};
  Square p{};
  if constexpr (N == kDynamicStates) {
    for (Array* v : {&g, &cr, &x, &next}) v->resize(nn);
    p.resize(nn * nn);
  }
  for (std::size_t i = 0; i < nn; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    for (std::size_t j = 0; j < nn; ++j) p[i * nn + j] = s.phi(ii, static_cast<Eigen::Index>(j));
    g[i] = s.gamma(ii);
    cr[i] = s.c(ii);
  }
  const Eigen::Index samples = ud.size();
  double z_prev = 0.0;
  for (Eigen::Index k = 0; k < samples; ++k) {
    double z = 0.0;
    for (std::size_t i = 0; i < nn; ++i) z += cr[i] * x[i];
    const double fb = feedback(z, (z - z_prev) / s.dt_s);
    z_prev = z;
    const double u_next = k + 1 < samples ? ud(k + 1) : ud(k);
    out(k) = z + s.d0 * (ud(k) - fb);
    const double drive = 0.5 * (ud(k) + u_next) - fb;
    for (std::size_t i = 0; i < nn; ++i) {
      double sum = g[i] * drive;
      for (std::size_t j = 0; j < nn; ++j) sum += p[i * nn + j] * x[j];
      next[i] = sum;
    }
    std::swap(x, next);
  }
}

template <int N>
void run_feedback_sized(Eigen::Index n, const FeedbackStep& s, const Eigen::VectorXd& ud,
                        const OutputFeedback& feedback, Eigen::VectorXd& out) {
  if constexpr (N > kMaxFixedStates) {
    run_feedback<kDynamicStates>(s, ud, feedback, out);
  } else if (n == N) {
    run_feedback<N>(s, ud, feedback, out);
  } else {
    run_feedback_sized<N + 1>(n, s, ud, feedback, out);
  }
}

}  // namespace

Eigen::VectorXd simulate_with_feedback(const model::TransferFunction& tf_in,
                                       const Eigen::VectorXd& u, double dt_s,
                                       const OutputFeedback& feedback) {
  if (!tf_in.is_proper()) throw std::invalid_argument("simulate_with_feedback: improper tf");
  const model::TransferFunction tf = model::monic(tf_in);
  const Eigen::Index n = tf.den.size() - 1, N = u.size();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  b.tail(tf.num.size()) = tf.num;
  const Eigen::VectorXd ud = delayed(u, tf.delay_s, dt_s);
  Eigen::VectorXd out(N);
  if (n == 0) {
    for (Eigen::Index k = 0; k < N; ++k) out(k) = b(0) * (ud(k) - feedback(0.0, 0.0));
    return out;
  }
  // Controllable canonical form x' = A x + e1 v, z = C x + D v, discretised exactly
  // (zero-order hold) through exp([[A, e1], [0, 0]] dt).
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 1, n + 1);
  m.block(0, 0, 1, n) = -tf.den.tail(n).transpose();
  for (Eigen::Index i = 1; i < n; ++i) m(i, i - 1) = 1.0;
  m(0, n) = 1.0;
  const Eigen::MatrixXd e = (m * dt_s).exp();
  const Eigen::MatrixXd phi = e.topLeftCorner(n, n);
  const Eigen::VectorXd gamma = e.topRightCorner(n, 1);
  const double d0 = b(0);
  const Eigen::RowVectorXd c = b.tail(n).transpose() - d0 * tf.den.tail(n).transpose();
  FeedbackStep step{phi, gamma, c, d0, dt_s};
  run_feedback_sized<1>(n, step, ud, feedback, out);
  return out;
}

Eigen::VectorXd smooth_zero_phase(const Eigen::VectorXd& x, double tau_s, double dt_s) {
  const Eigen::Index n = x.size();
  if (n == 0) return x;
  const double a = std::exp(-dt_s / std::max(tau_s, 1e-12));
  const Eigen::Index head =
      std::min<Eigen::Index>(n, std::max<Eigen::Index>(1, std::llround(tau_s / dt_s)));
  Eigen::VectorXd f(n);
  double s = x.head(head).mean();
  for (Eigen::Index k = 0; k < n; ++k) f(k) = s = a * s + (1.0 - a) * x(k);
  s = f.tail(head).mean();
  for (Eigen::Index k = n - 1; k >= 0; --k) f(k) = s = a * s + (1.0 - a) * f(k);
  return f;
}

}  // namespace rig::diagnose
