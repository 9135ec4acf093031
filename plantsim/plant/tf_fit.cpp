// Frequency-domain fits used by the linearisation: a rational function by Sanathanan-Koerner
// iterations and the best second order plus dead time.
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>

#include "plantsim/plant/linearise.hpp"

namespace plantsim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::complex<double> polyval_low_first(const Eigen::VectorXd& c, std::complex<double> s) {
  std::complex<double> v{0.0, 0.0};
  for (Eigen::Index k = c.size() - 1; k >= 0; --k) v = v * s + c[k];
  return v;
}

bool stable(const Eigen::VectorXd& den_low_first) {
  const Eigen::Index n = den_low_first.size() - 1;
  if (n < 1) return true;
  Eigen::MatrixXd comp = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) comp(0, i) = -den_low_first[n - 1 - i] / den_low_first[n];
  for (Eigen::Index i = 1; i < n; ++i) comp(i, i - 1) = 1.0;
  const Eigen::VectorXcd roots = comp.eigenvalues();
  return (roots.array().real() < 0.0).all();
}

}  // namespace

// Sanathanan-Koerner: with D(0) = 1, minimise sum |(N(s_i) - g_i D(s_i)) / (g_i D_prev(s_i))|^2,
// i.e. the relative error, linear in the coefficients at each pass. s is scaled by w0 (the
// geometric mean of the band) so the powers stay near 1.
bool fit_rational(const Eigen::VectorXd& freqs_hz, const Eigen::VectorXcd& g, int n, int m,
                  Eigen::VectorXd* num, Eigen::VectorXd* den) {
  const Eigen::Index nf = freqs_hz.size();
  const double w0 = kTwoPi * std::sqrt(freqs_hz.minCoeff() * freqs_hz.maxCoeff());
  Eigen::VectorXd a = Eigen::VectorXd::Zero(n + 1);
  a[0] = 1.0;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(m + 1);
  const int unknowns = (m + 1) + n;
  for (int pass = 0; pass < 30; ++pass) {
    Eigen::MatrixXd lhs(2 * nf, unknowns);
    Eigen::VectorXd rhs(2 * nf);
    for (Eigen::Index i = 0; i < nf; ++i) {
      const std::complex<double> s{0.0, kTwoPi * freqs_hz[i] / w0};
      const std::complex<double> w = 1.0 / (g[i] * polyval_low_first(a, s));
      std::complex<double> sk{1.0, 0.0};
      for (int k = 0; k <= m; ++k, sk *= s) {
        lhs(2 * i, k) = (w * sk).real();
        lhs(2 * i + 1, k) = (w * sk).imag();
      }
      sk = s;
      for (int k = 1; k <= n; ++k, sk *= s) {
        const std::complex<double> v = -w * g[i] * sk;
        lhs(2 * i, m + k) = v.real();
        lhs(2 * i + 1, m + k) = v.imag();
      }
      rhs(2 * i) = (w * g[i]).real();
      rhs(2 * i + 1) = (w * g[i]).imag();
    }
    const Eigen::VectorXd scale = lhs.colwise().norm().cwiseMax(1e-300).cwiseInverse();
    const Eigen::VectorXd z = (lhs * scale.asDiagonal()).colPivHouseholderQr().solve(rhs);
    const Eigen::VectorXd theta = z.cwiseProduct(scale);
    if (!theta.allFinite()) return false;
    b = theta.head(m + 1);
    a.tail(n) = theta.tail(n);
  }
  if (!stable(a)) return false;
  // Undo the frequency scaling (coefficient of s^k divided by w0^k), make den monic and
  // order highest power first.
  const double lead = a[n] / std::pow(w0, n);
  num->resize(m + 1);
  den->resize(n + 1);
  for (int k = 0; k <= m; ++k) (*num)[m - k] = b[k] / std::pow(w0, k) / lead;
  for (int k = 0; k <= n; ++k) (*den)[n - k] = a[k] / std::pow(w0, k) / lead;
  return true;
}

std::complex<double> SopdtFit::response(double freq_hz) const {
  const std::complex<double> s{0.0, kTwoPi * freq_hz};
  const double wn = kTwoPi * fn_hz;
  return gain_kw_per_pct * std::exp(-s * delay_s) / (s * s / (wn * wn) + 2.0 * zeta * s / wn + 1.0);
}

// Gauss-Newton on the complex log error log(model/H) (gain and phase errors weighted alike),
// started from several delays; the best local optimum wins.
SopdtFit fit_sopdt(const LinearModel& model, double lo_hz, double hi_hz) {
  constexpr int kPoints = 200;
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(kPoints, lo_hz, hi_hz);
  Eigen::VectorXcd h(kPoints);
  for (int i = 0; i < kPoints; ++i) h[i] = model.response(f[i]);
  auto residual = [&](const Eigen::Vector4d& x) {
    SopdtFit m{x[0], x[1], x[2], x[3]};
    Eigen::VectorXd r(2 * kPoints);
    for (int i = 0; i < kPoints; ++i) {
      const std::complex<double> e = std::log(m.response(f[i]) / h[i]);
      r[2 * i] = e.real();
      r[2 * i + 1] = e.imag();
    }
    return r;
  };
  Eigen::Index peak = 0;
  h.cwiseAbs().maxCoeff(&peak);
  double best_cost = INFINITY;
  Eigen::Vector4d best = Eigen::Vector4d::Zero();
  for (double t0 = 0.0; t0 <= 0.15; t0 += 0.025) {
    Eigen::Vector4d x{model.dc_gain_kw_per_pct, f[peak], 0.1, t0};
    for (int it = 0; it < 60; ++it) {
      const Eigen::VectorXd r = residual(x);
      Eigen::MatrixXd jac(r.size(), 4);
      for (int j = 0; j < 4; ++j) {
        Eigen::Vector4d dx = Eigen::Vector4d::Zero();
        dx[j] = 1e-7 * std::max(1.0, std::abs(x[j]));
        jac.col(j) = (residual(x + dx) - r) / dx[j];
      }
      const Eigen::Vector4d step = jac.colPivHouseholderQr().solve(-r);
      if (!step.allFinite()) break;
      x += step;
      if (step.norm() < 1e-12) break;
    }
    const double cost = residual(x).squaredNorm();
    if (std::isfinite(cost) && cost < best_cost && x[2] > 0.0) {
      best_cost = cost;
      best = x;
    }
  }
  SopdtFit out{best[0], best[1], best[2], best[3]};
  const Eigen::VectorXd r = residual(best);
  for (int i = 0; i < kPoints; ++i) {
    out.max_error_db = std::max(out.max_error_db, std::abs(r[2 * i]) * 20.0 / std::log(10.0));
    out.max_error_deg =
        std::max(out.max_error_deg, std::abs(r[2 * i + 1]) * 180.0 / std::numbers::pi);
  }
  return out;
}

}  // namespace plantsim
