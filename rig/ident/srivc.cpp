// SRIVC (Young 1976; Garnier, Mensler and Richard 2003; CONTSID srivc).
#include "rig/ident/srivc.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace rig::ident {
namespace {

constexpr double kGolden = 0.6180339887498949;

// (p + lambda)^n expanded, highest power first.
Eigen::VectorXd svf_denominator(int n, double lambda) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n + 1);
  c(0) = 1.0;
  for (int k = 0; k < n; ++k)
    for (int i = k + 1; i >= 1; --i) c(i) += lambda * c(i - 1);
  return c;
}

// Reflect right-half-plane roots so the prefilter 1/A stays stable.
Eigen::VectorXd stabilised(const Eigen::VectorXd& den) {
  if (!den.allFinite()) return {};  // caller treats an empty result as a failed iterate
  model::TransferFunction tf{Eigen::VectorXd::Ones(1), den, 0.0};
  const Eigen::VectorXcd p = tf.poles();
  bool ok = true;
  for (Eigen::Index i = 0; i < p.size(); ++i) ok = ok && p(i).real() < 0.0;
  if (ok) return den;
  Eigen::VectorXcd poly = Eigen::VectorXcd::Zero(p.size() + 1);
  poly(0) = 1.0;
  for (Eigen::Index k = 0; k < p.size(); ++k) {
    const std::complex<double> r(-std::abs(p(k).real()) - 1e-6, p(k).imag());
    for (Eigen::Index i = k + 1; i >= 1; --i) poly(i) -= r * poly(i - 1);
  }
  return poly.real();
}

struct IvStep {
  Eigen::VectorXd theta;  // [a_{n-1}..a_0, b_m..b_0]
  bool ok = false;
};

// Rows of the regression: every record's samples but its filters' start-up transient
// (unknown initial conditions of the record).
std::vector<Eigen::Index> regression_rows(Eigen::Index n, const model::RecordStarts& starts) {
  const model::RecordStarts s = starts.empty() ? model::RecordStarts{0} : starts;
  std::vector<Eigen::Index> rows;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Eigen::Index end = i + 1 < s.size() ? s[i + 1] : n;
    const Eigen::Index skip = std::min<Eigen::Index>((end - s[i]) / 10, 200);
    for (Eigen::Index k = s[i] + skip; k < end; ++k) rows.push_back(k);
  }
  return rows;
}

// One (I)V solve with prefilter 1/A; instruments from x_hat when given, else plain LS.
IvStep iv_step(const Eigen::VectorXd& a_filter, const Eigen::VectorXd& u, const Eigen::VectorXd& y,
               const Eigen::VectorXd* x_hat, double dt_s, model::ModelOrder order, double delay_s,
               const model::RecordStarts& starts) {
  const int n = order.n, m = order.m;
  const Eigen::MatrixXd yf = model::filtered_derivatives(a_filter, y, dt_s, 0.0, starts);
  const Eigen::MatrixXd uf = model::filtered_derivatives(a_filter, u, dt_s, delay_s, starts);
  const Eigen::MatrixXd xf =
      x_hat ? model::filtered_derivatives(a_filter, *x_hat, dt_s, 0.0, starts) : yf;
  const std::vector<Eigen::Index> idx = regression_rows(y.size(), starts);
  const Eigen::Index rows = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd phi(rows, n + m + 1), zeta(rows, n + m + 1);
  phi.leftCols(n) = -yf(idx, Eigen::seqN(1, n));
  zeta.leftCols(n) = -xf(idx, Eigen::seqN(1, n));
  phi.rightCols(m + 1) = uf(idx, Eigen::seqN(n - m, m + 1));
  zeta.rightCols(m + 1) = phi.rightCols(m + 1);
  const Eigen::VectorXd target = yf(idx, 0);
  const Eigen::MatrixXd zp = zeta.transpose() * phi;
  if (!zp.allFinite()) return {};
  Eigen::FullPivLU<Eigen::MatrixXd> lu(zp);
  if (!lu.isInvertible()) return {};
  IvStep step{lu.solve(zeta.transpose() * target), true};
  step.ok = step.theta.allFinite();
  return step;
}

model::TransferFunction tf_from(const Eigen::VectorXd& theta, model::ModelOrder order,
                                double delay_s) {
  model::TransferFunction tf;
  tf.den.resize(order.n + 1);
  tf.den << 1.0, theta.head(order.n);
  tf.num = theta.tail(order.m + 1);
  tf.delay_s = delay_s;
  return tf;
}

double output_sse(const model::TransferFunction& tf, const Eigen::VectorXd& u,
                  const Eigen::VectorXd& y, double dt_s, const model::RecordStarts& starts) {
  if (!tf.is_stable()) return std::numeric_limits<double>::infinity();
  const double sse = (y - simulate(tf, u, dt_s, starts)).squaredNorm();
  return std::isfinite(sse) ? sse : std::numeric_limits<double>::infinity();
}

struct FixedDelayFit {
  model::TransferFunction tf;
  double sse = std::numeric_limits<double>::infinity();
  int iterations = 0;
  bool converged = false;
};

// SRIVC at a fixed delay from the denominator a_start.
FixedDelayFit srivc_fixed(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                          model::ModelOrder order, double delay_s, const Eigen::VectorXd& a_start,
                          const SrivcOptions& opt) {
  FixedDelayFit fit;
  IvStep st = iv_step(a_start, u, y, nullptr, dt_s, order, delay_s, opt.starts);
  if (!st.ok) return fit;
  Eigen::VectorXd theta = st.theta;
  for (int it = 1; it <= opt.max_iterations; ++it) {
    model::TransferFunction tf = tf_from(theta, order, delay_s);
    tf.den = stabilised(tf.den);
    if (tf.den.size() != order.n + 1) break;  // degenerate iterate: keep the last theta
    const Eigen::VectorXd x_hat = simulate(tf, u, dt_s, opt.starts);
    const IvStep next = iv_step(tf.den, u, y, &x_hat, dt_s, order, delay_s, opt.starts);
    fit.iterations = it;
    if (!next.ok) break;
    const double change = (next.theta - theta).norm() / std::max(1e-300, theta.norm());
    theta = next.theta;
    if (change < opt.tolerance) {
      fit.converged = true;
      break;
    }
  }
  fit.tf = tf_from(theta, order, delay_s);
  fit.sse = output_sse(fit.tf, u, y, dt_s, opt.starts);
  return fit;
}

// Start: SVF least squares over a few filter cut-offs, keeping the best output error.
Eigen::VectorXd initial_denominator(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                                    model::ModelOrder order, double delay_s,
                                    const SrivcOptions& opt) {
  std::vector<double> lambdas;
  if (opt.svf_cutoff_rad_s > 0) {
    lambdas.push_back(opt.svf_cutoff_rad_s);
  } else {
    for (double k : {0.02, 0.05, 0.12}) lambdas.push_back(2.0 * M_PI * k / dt_s);
  }
  Eigen::VectorXd best = svf_denominator(order.n, lambdas.front());
  double best_sse = std::numeric_limits<double>::infinity();
  for (double l : lambdas) {
    const Eigen::VectorXd a = svf_denominator(order.n, l);
    const IvStep st = iv_step(a, u, y, nullptr, dt_s, order, delay_s, opt.starts);
    if (!st.ok) continue;
    model::TransferFunction tf = tf_from(st.theta, order, delay_s);
    tf.den = stabilised(tf.den);
    if (tf.den.size() != order.n + 1) continue;
    const double sse = output_sse(tf, u, y, dt_s, opt.starts);
    if (sse < best_sse) best_sse = sse, best = tf.den;
  }
  return best;
}

// Dead time minimising the output error: a coarse grid with a few SRIVC iterations per point,
// golden section on the best bracket, then full convergence at the optimum.
FixedDelayFit search_delay(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                           model::ModelOrder order, const Eigen::VectorXd& a_start,
                           FixedDelayFit best, const SrivcOptions& opt) {
  SrivcOptions quick = opt;
  quick.max_iterations = std::min(opt.max_iterations, 4);
  quick.tolerance = std::max(opt.tolerance, 1e-5);
  const int grid = std::max(3, std::min(8, static_cast<int>(opt.max_delay_s / dt_s) + 1));
  const double step = opt.max_delay_s / (grid - 1);
  int best_i = 0;
  for (int i = 1; i < grid; ++i) {
    FixedDelayFit f = srivc_fixed(u, y, dt_s, order, i * step, a_start, quick);
    if (f.sse < best.sse) best = f, best_i = i;
  }
  double a = std::max(0.0, (best_i - 1) * step), b = std::min(opt.max_delay_s, (best_i + 1) * step);
  // A start whose every fit failed has no model: warm-start from a_start instead of an
  // empty denominator.
  const Eigen::VectorXd warm = best.tf.den.size() == order.n + 1 ? best.tf.den : a_start;
  auto eval = [&](double td) { return srivc_fixed(u, y, dt_s, order, td, warm, quick); };
  double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
  FixedDelayFit f1 = eval(x1), f2 = eval(x2);
  while (b - a > dt_s / 100.0) {
    if (f1.sse <= f2.sse) {
      b = x2, x2 = x1, f2 = f1, x1 = b - kGolden * (b - a), f1 = eval(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + kGolden * (b - a), f2 = eval(x2);
    }
  }
  for (const FixedDelayFit* f : {&f1, &f2})
    if (f->sse < best.sse) best = *f;
  if (!std::isfinite(best.sse)) return best;  // no stable fit at any delay
  const FixedDelayFit final_fit = srivc_fixed(u, y, dt_s, order, best.tf.delay_s, best.tf.den, opt);
  return final_fit.sse <= best.sse ? final_fit : best;
}

}  // namespace

Eigen::MatrixXd output_sensitivities(const model::TransferFunction& tf_in, const Eigen::VectorXd& u,
                                     double dt_s, const model::RecordStarts& starts) {
  const model::TransferFunction tf = model::monic(tf_in);
  const int n = tf.order(), m = static_cast<int>(tf.num.size()) - 1;
  // y_hat = B/A u_d: d/da_i = -p^i/A y_hat, d/db_j = p^j/A u_d, d/dTd = -p B/A u_d.
  const Eigen::VectorXd y_hat = simulate(tf, u, dt_s, starts);
  const Eigen::MatrixXd xf = model::filtered_derivatives(tf.den, y_hat, dt_s, 0.0, starts);
  const Eigen::MatrixXd uf = model::filtered_derivatives(tf.den, u, dt_s, tf.delay_s, starts);
  Eigen::MatrixXd j(u.size(), n + m + 2);
  j.leftCols(n) = -xf.rightCols(n);
  j.middleCols(n, m + 1) = uf.rightCols(m + 1);
  if (m < n) {
    Eigen::VectorXd b_shift = Eigen::VectorXd::Zero(n + 1);  // p B(p), padded
    b_shift.segment(n - m - 1, m + 1) = tf.num;
    j.col(n + m + 1) = -(uf * b_shift);
  } else {
    // Biproper: central difference of the simulated output.
    const double h = 0.1 * dt_s;
    model::TransferFunction lo = tf, hi = tf;
    lo.delay_s = std::max(0.0, tf.delay_s - h);
    hi.delay_s = tf.delay_s + h;
    j.col(n + m + 1) =
        (simulate(hi, u, dt_s, starts) - simulate(lo, u, dt_s, starts)) / (hi.delay_s - lo.delay_s);
  }
  return j;
}

SrivcResult estimate_srivc(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                           const SrivcOptions& opt) {
  const model::ModelOrder order = opt.order;
  if (u.size() != y.size() || u.size() < 20 * (order.n + order.m + 2))
    throw std::invalid_argument("estimate_srivc: u and y must be equally long and >= 20 p samples");
  if (order.n < 1 || order.m < 0 || order.m >= order.n + 1 || !(dt_s > 0.0))
    throw std::invalid_argument("estimate_srivc: need n >= 1, 0 <= m <= n and dt_s > 0");
  const double td0 = opt.delay_s.value_or(0.0);
  const Eigen::VectorXd a0 = initial_denominator(u, y, dt_s, order, td0, opt);
  FixedDelayFit best = srivc_fixed(u, y, dt_s, order, td0, a0, opt);
  if (!opt.delay_s) best = search_delay(u, y, dt_s, order, a0, best, opt);
  // Singular instruments or an unstable final iterate at every delay: no usable model.
  if (!std::isfinite(best.sse))
    throw std::invalid_argument("estimate_srivc: no stable model of order " +
                                std::to_string(order.n) + "/" + std::to_string(order.m) +
                                " (singular instrument matrix or unstable iterate)");
  SrivcResult res;
  res.model = best.tf;
  res.delay_s = best.tf.delay_s;
  res.iterations = best.iterations;
  res.converged = best.converged;
  const Eigen::Index N = y.size(), p = order.n + order.m + 2;
  res.noise_variance = best.sse / static_cast<double>(N - p);
  res.fit_pct = model::fit_percent(y, simulate(res.model, u, dt_s, opt.starts));
  // Output-error covariance sigma^2 (J^T J)^-1, J the output sensitivities (incl. Td).
  const Eigen::MatrixXd jac = output_sensitivities(res.model, u, dt_s, opt.starts);
  Eigen::MatrixXd info = jac.transpose() * jac;
  if (opt.delay_s) info.col(p - 1).setZero(), info.row(p - 1).setZero(), info(p - 1, p - 1) = 1;
  res.covariance = res.noise_variance * info.inverse();
  if (opt.delay_s) res.covariance(p - 1, p - 1) = 0.0;
  res.delay_std_s = std::sqrt(std::max(0.0, res.covariance(p - 1, p - 1)));
  // Covariance on the full theta = [a_n..a_0, b_m..b_0] layout (a_n = 1 fixed).
  Eigen::MatrixXd cov_full = Eigen::MatrixXd::Zero(p, p);
  cov_full.bottomRightCorner(p - 1, p - 1) = res.covariance.topLeftCorner(p - 1, p - 1);
  res.parameters = parameter_table(res.model, cov_full, res.delay_std_s);
  res.derived = derived_figures(res.model, cov_full);
  return res;
}

}  // namespace rig::ident
