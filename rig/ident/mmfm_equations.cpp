// The MMFM equation set for one configuration and its (total) least-squares solution.
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "rig/ident/mmfm.hpp"

namespace rig::ident {
namespace {

// Columns i = 0..deriv of (-1)^i S^i phi_k^(i) sampled on tau, for function k of the family.
// Hermite: (-1)^i S^i phi_k^(i) = phi_{k+i}.
Eigen::MatrixXd function_columns(const Eigen::VectorXd& tau, double centre_s,
                                 const MmfmSettings& st, int k, int deriv,
                                 const Eigen::MatrixXd* hermite_cache) {
  if (st.family == ModulatingFamily::kHermite) return hermite_cache->middleCols(k, deriv + 1);
  const double hw = 4.0 * st.scale_s;
  Eigen::MatrixXd d =
      polynomial_function_derivatives(tau, centre_s - hw, centre_s + hw, deriv + 1 + k, deriv);
  for (int i = 0; i <= deriv; ++i) d.col(i) *= std::pow(-st.scale_s, i);
  return d;
}

struct Equations {
  Eigen::MatrixXd m;  // rows: equations, columns: scaled theta [a_n..a_0, b_m..b_0]
};

// Index range of the lags within centre +- half_width on c's lag axis.
std::pair<Eigen::Index, Eigen::Index> support(const signal::Correlation& c, double centre_s,
                                              double half_width_s) {
  const double lo = (centre_s - half_width_s) / c.dt_s + static_cast<double>(c.zero_index);
  const double hi = (centre_s + half_width_s) / c.dt_s + static_cast<double>(c.zero_index);
  const Eigen::Index i0 =
      std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::floor(lo)), 0, c.size() - 1);
  const Eigen::Index i1 =
      std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::ceil(hi)), 0, c.size() - 1);
  return {i0, i1 - i0 + 1};
}

// Rows for the functions of one band (scale band_s, its centres). Unknowns are scaled with
// the primary S: a_i S^-i, so the band's columns carry (S / band_s)^i.
void add_band_rows(const signal::Correlation& ruu, const signal::Correlation& ryu,
                   model::ModelOrder order, double delay_s, const MmfmSettings& st, double band_s,
                   const std::vector<double>& centres, Eigen::MatrixXd& m, Eigen::Index& row) {
  const int n = order.n, mo = order.m, deriv = std::max(n, mo);
  MmfmSettings band = st;
  band.scale_s = band_s;
  const double hw = support_half_width_s(order, band), ratio = st.scale_s / band_s;
  for (double c : centres) {
    // Only the lags inside the support carry weight; the functions are ~0 elsewhere.
    const auto [y0, ny] = support(ryu, c, hw);
    const auto [u0, nu] = support(ruu, c - delay_s, hw);
    Eigen::VectorXd ty(ny), tu(nu);
    for (Eigen::Index i = 0; i < ny; ++i) ty(i) = ryu.lag_s(y0 + i);
    for (Eigen::Index i = 0; i < nu; ++i) tu(i) = ruu.lag_s(u0 + i);
    const Eigen::VectorXd ry = ryu.r.segment(y0, ny), ru = ruu.r.segment(u0, nu);
    Eigen::MatrixXd hy, hu;
    if (band.family == ModulatingFamily::kHermite) {
      hy = hermite_functions(ty, c, band_s, band.functions + deriv);
      hu = hermite_functions(tu, c - delay_s, band_s, band.functions + deriv);
    }
    for (int k = 0; k < band.functions; ++k, ++row) {
      const Eigen::MatrixXd fy = function_columns(ty, c, band, k, deriv, &hy);
      const Eigen::MatrixXd fu = function_columns(tu, c - delay_s, band, k, deriv, &hu);
      // <phi, r> by the trapezoid rule (the functions vanish at the support ends).
      const Eigen::VectorXd gy = fy.transpose() * ry * ryu.dt_s;
      const Eigen::VectorXd gu = fu.transpose() * ru * ruu.dt_s;
      // Weight each equation by its function's size, not by the data (rows where the
      // correlations vanish must stay small).
      const double w = 1.0 / (fy.colwise().norm().maxCoeff() * std::sqrt(ryu.dt_s));
      for (int i = 0; i <= n; ++i) m(row, n - i) = gy(i) * w * std::pow(ratio, i);
      for (int j = 0; j <= mo; ++j) m(row, n + 1 + mo - j) = -gu(j) * w * std::pow(ratio, j);
    }
  }
}

Equations build_equations(const signal::Correlation& ruu, const signal::Correlation& ryu,
                          model::ModelOrder order, double delay_s, const MmfmSettings& st) {
  Eigen::Index rows = static_cast<Eigen::Index>(st.centres_s.size());
  for (const MmfmBand& b : st.extra_bands) rows += static_cast<Eigen::Index>(b.centres_s.size());
  Equations eq;
  eq.m.resize(rows * st.functions, order.n + order.m + 2);
  Eigen::Index row = 0;
  add_band_rows(ruu, ryu, order, delay_s, st, st.scale_s, st.centres_s, eq.m, row);
  for (const MmfmBand& b : st.extra_bands)
    add_band_rows(ruu, ryu, order, delay_s, st, b.scale_s, b.centres_s, eq.m, row);
  return eq;
}

void check_axes(const signal::Correlation& ruu, const signal::Correlation& ryu) {
  if (ruu.size() != ryu.size() || ruu.zero_index != ryu.zero_index ||
      std::abs(ruu.dt_s - ryu.dt_s) > 1e-12 * ruu.dt_s || !(ruu.dt_s > 0.0))
    throw std::invalid_argument("mmfm: ruu and ryu must share size, zero_index and dt_s (> 0)");
}

}  // namespace

const char* to_string(MmfmSolver solver) {
  return solver == MmfmSolver::kLeastSquares ? "least squares" : "total least squares";
}

double support_half_width_s(model::ModelOrder order, const MmfmSettings& settings) {
  if (settings.family == ModulatingFamily::kPolynomial) return 4.0 * settings.scale_s;
  return hermite_half_width(settings.functions - 1 + std::max(order.n, order.m)) * settings.scale_s;
}

std::vector<double> admissible_centres(const signal::Correlation& ruu,
                                       const signal::Correlation& ryu, model::ModelOrder order,
                                       double min_delay_s, double max_delay_s,
                                       const MmfmSettings& settings, int count) {
  const double hw = support_half_width_s(order, settings);
  const double y0 = ryu.lag_s(0), y1 = ryu.lag_s(ryu.size() - 1);
  const double u0 = ruu.lag_s(0), u1 = ruu.lag_s(ruu.size() - 1);
  double lo = std::max(y0 + hw, u0 + hw + max_delay_s);
  double hi = std::min(y1 - hw, u1 - hw + min_delay_s);
  if (hi < lo || count < 1) return {};
  // Keep the centres near where r_yu carries signal (|r_yu| above 5 % of its peak).
  const double peak = ryu.r.cwiseAbs().maxCoeff();
  Eigen::Index first = 0, last = ryu.size() - 1;
  while (first < last && std::abs(ryu.r(first)) < 0.05 * peak) ++first;
  while (last > first && std::abs(ryu.r(last)) < 0.05 * peak) --last;
  const double sig_lo = ryu.lag_s(first) - 0.5 * hw, sig_hi = ryu.lag_s(last) + 0.5 * hw;
  if (std::max(lo, sig_lo) <= std::min(hi, sig_hi)) {
    lo = std::max(lo, sig_lo);
    hi = std::min(hi, sig_hi);
  }
  // At least `count` centres, and enough that neighbouring supports overlap by a third.
  count = std::min(64, std::max(count, static_cast<int>(std::ceil(1.5 * (hi - lo) / hw)) + 1));
  std::vector<double> centres;
  for (int i = 0; i < count; ++i)
    centres.push_back(count == 1 ? 0.5 * (lo + hi) : lo + (hi - lo) * i / (count - 1.0));
  return centres;
}

signal::Correlation model_cross_correlation(const model::TransferFunction& tf,
                                            const signal::Correlation& ruu) {
  signal::Correlation out = ruu;
  out.r = simulate(tf, ruu.r, ruu.dt_s);
  return out;
}

signal::Correlation model_cross_correlation(const model::TransferFunction& tf,
                                            const signal::Correlation& ruu,
                                            const signal::Correlation& ryu) {
  signal::Correlation out = model_cross_correlation(tf, ruu);
  const Eigen::MatrixXd basis = model::free_response_basis(tf, ruu.size(), ruu.dt_s);
  if (basis.cols() == 0 || !out.r.allFinite()) return out;
  const Eigen::VectorXd x0 = basis.colPivHouseholderQr().solve(ryu.r - out.r);
  out.r += basis * x0;
  return out;
}

namespace {

struct Solution {
  Eigen::VectorXd theta_t;  // equilibrated unknowns, theta_t(ref) = 1
  Eigen::MatrixXd cov_t;    // their covariance (zero row/column at ref)
  Eigen::VectorXd residual;
  double condition_number = 0.0;
};

// LS with theta_t(ref) = 1, or TLS (smallest right singular vector, rescaled), of mt theta = 0.
// Covariance s^2 (A^T A)^-1 = s^2 V diag(1/sv^2) V^T for A = mt without column ref.
Solution solve_equilibrated(const Eigen::MatrixXd& mt, Eigen::Index ref, MmfmSolver solver) {
  const Eigen::Index rows = mt.rows(), p = mt.cols();
  Eigen::MatrixXd a(rows, p - 1);
  a << mt.leftCols(ref), mt.rightCols(p - 1 - ref);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd_a(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  Solution sol;
  sol.theta_t.resize(p);
  if (solver == MmfmSolver::kLeastSquares) {
    const Eigen::VectorXd z = svd_a.solve(-mt.col(ref));
    sol.theta_t << z.head(ref), 1.0, z.tail(p - 1 - ref);
    const Eigen::VectorXd sv = svd_a.singularValues();
    sol.condition_number = sv(0) / sv(sv.size() - 1);
  } else {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(mt, Eigen::ComputeThinV);
    sol.theta_t = svd.matrixV().col(p - 1) / svd.matrixV()(ref, p - 1);
    const Eigen::VectorXd sv = svd.singularValues();
    sol.condition_number = sv(0) / sv(p - 2);
  }
  sol.residual = mt * sol.theta_t;
  const double s2 = sol.residual.squaredNorm() / std::max<Eigen::Index>(1, rows - (p - 1));
  const Eigen::VectorXd inv_sv2 = svd_a.singularValues().array().square().inverse().matrix();
  const Eigen::MatrixXd cov_z =
      s2 * svd_a.matrixV() * inv_sv2.asDiagonal() * svd_a.matrixV().transpose();
  sol.cov_t = Eigen::MatrixXd::Zero(p, p);
  auto full = [ref](Eigen::Index i) { return i < ref ? i : i + 1; };
  for (Eigen::Index i = 0; i < p - 1; ++i)
    for (Eigen::Index j = 0; j < p - 1; ++j) sol.cov_t(full(i), full(j)) = cov_z(i, j);
  return sol;
}

}  // namespace

MmfmResult mmfm_solve(const signal::Correlation& ruu, const signal::Correlation& ryu,
                      model::ModelOrder order, double delay_s, const MmfmSettings& st) {
  check_axes(ruu, ryu);
  if (order.n < 1 || order.m < 0 || order.m > order.n)
    throw std::invalid_argument("mmfm: order must satisfy n >= 1 and 0 <= m <= n");
  const int p = order.n + order.m + 2;
  if (st.centres_s.empty() || st.functions * static_cast<int>(st.centres_s.size()) < p - 1)
    throw std::invalid_argument("mmfm: fewer equations than unknowns (add functions/centres)");
  const Equations eq = build_equations(ruu, ryu, order, delay_s, st);
  Eigen::VectorXd col_norm = eq.m.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < p; ++j)
    if (col_norm(j) == 0.0) col_norm(j) = 1.0;
  const Eigen::MatrixXd mt = eq.m * col_norm.cwiseInverse().asDiagonal();
  const Eigen::Index ref = st.normalisation == Normalisation::kMonicDen ? 0 : p - 1;
  const Solution sol = solve_equilibrated(mt, ref, st.solver);
  // Undo the equilibration and the time scaling: theta_i = theta_t_i / norm_i * S^power_i.
  Eigen::VectorXd unscale(p);
  for (int i = 0; i <= order.n; ++i) unscale(order.n - i) = std::pow(st.scale_s, i);
  for (int j = 0; j <= order.m; ++j) unscale(order.n + 1 + order.m - j) = std::pow(st.scale_s, j);
  unscale = unscale.cwiseQuotient(col_norm);
  Eigen::MatrixXd cov = unscale.asDiagonal() * sol.cov_t * unscale.asDiagonal();
  const model::TransferFunction raw =
      unpack_parameters(sol.theta_t.cwiseProduct(unscale), order, delay_s);
  MmfmResult res;
  res.model = normalise(raw, st.normalisation, &cov);
  res.covariance = cov;
  res.condition_number = sol.condition_number;
  res.delay_s = delay_s;
  res.equations = static_cast<int>(eq.m.rows());
  res.equation_residual = sol.residual.norm() / std::max(1e-300, mt.col(ref).norm());
  res.settings = st;
  res.model_ryu = model_cross_correlation(res.model, ruu, ryu);
  res.correlation_fit_pct = model::fit_percent(ryu.r, res.model_ryu.r);
  res.derived = derived_figures(res.model, res.covariance);
  res.parameters = parameter_table(res.model, res.covariance, res.delay_std_s);
  return res;
}

}  // namespace rig::ident
