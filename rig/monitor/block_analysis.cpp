#include "rig/monitor/block_analysis.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

namespace rig::monitor {
namespace {

double power_at(const Eigen::VectorXd& x, double dt_s, double f_hz) {
  // Goertzel-like direct sum (one frequency), Hann window against leakage of the excitation.
  const Eigen::Index n = x.size();
  std::complex<double> acc{0.0, 0.0};
  const double w = 2.0 * std::numbers::pi * f_hz * dt_s;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double hann = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * k / (n - 1));
    acc += hann * x(k) * std::polar(1.0, -w * static_cast<double>(k));
  }
  return std::norm(acc);
}

}  // namespace

// Welch averaging: a single periodogram bin is exponentially distributed, whose logarithm has
// a long tail; the mean of half-overlapping segments is close to Gaussian in log.
constexpr Eigen::Index kSegmentsPerBlock = 4;  // segment = block / 4, 7 with half overlap

double line_log_ratio(const Eigen::VectorXd& x, double dt_s, double f_hz) {
  const double nyquist = 0.5 / dt_s;
  const Eigen::Index len = std::max<Eigen::Index>(16, x.size() / kSegmentsPerBlock);
  const double bin = 1.0 / (static_cast<double>(len) * dt_s);
  if (x.size() < len || !(f_hz > 8.0 * bin) || f_hz + 8.0 * bin >= nyquist) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double line = 0.0, floor = 0.0;
  int segments = 0, count = 0;
  for (Eigen::Index start = 0; start + len <= x.size(); start += len / 2) {
    const Eigen::VectorXd seg = x.segment(start, len);
    line += power_at(seg, dt_s, f_hz);
    ++segments;
    for (int j = 3; j <= 8; ++j) {
      floor += power_at(seg, dt_s, f_hz + j * bin) + power_at(seg, dt_s, f_hz - j * bin);
      count += 2;
    }
  }
  return std::log10(std::max(line / segments, 1e-30) / std::max(floor / count, 1e-30));
}

BlockFit analyse_block(const std::vector<model::TransferFunction>& models,
                       const std::vector<double>& probes, const Eigen::VectorXd& u_c,
                       const Eigen::VectorXd& y_c, double dt_s, double speed_rpm) {
  const Eigen::Index n = y_c.size();
  const Eigen::Index p = static_cast<Eigen::Index>(probes.size());
  BlockFit f;
  f.parameters = static_cast<int>(p);
  const Eigen::VectorXd y0 = model::simulate(models[0], u_c, dt_s).tail(n);
  Eigen::MatrixXd s(n, p);
  for (Eigen::Index i = 0; i < p; ++i) {
    s.col(i) = (model::simulate(models[static_cast<std::size_t>(i + 1)], u_c, dt_s).tail(n) - y0) /
               probes[static_cast<std::size_t>(i)];
  }
  const Eigen::VectorXd r = y_c - y0;
  const double rr = r.squaredNorm();
  f.residual_rms_kw = std::sqrt(rr / static_cast<double>(n));
  f.response_rms_kw = std::sqrt(y0.squaredNorm() / static_cast<double>(n));
  f.normal = s.transpose() * s;
  f.rhs = s.transpose() * r;
  f.single.resize(p);
  f.explained.resize(p);
  for (Eigen::Index i = 0; i < p; ++i) {
    const double ss = f.normal(i, i);
    f.single(i) = ss > 0.0 ? f.rhs(i) / ss : 0.0;
    f.explained(i) = ss > 0.0 && rr > 0.0 ? f.rhs(i) * f.rhs(i) / ss / rr : 0.0;
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(f.normal);
  f.joint = ldlt.solve(f.rhs);
  const Eigen::MatrixXd inv = ldlt.solve(Eigen::MatrixXd::Identity(p, p));
  const double dof = std::max<double>(1.0, static_cast<double>(n - p));
  const double s2 = (r - s * f.joint).squaredNorm() / dof;
  f.fit_residual_rms_kw = std::sqrt(s2);
  f.joint_se = (s2 * inv.diagonal().cwiseMax(0.0)).cwiseSqrt();
  f.line_hz = speed_rpm > 0.0 ? speed_rpm / 120.0 : 0.0;
  f.line_log_ratio = f.line_hz > 0.0 ? line_log_ratio(r, dt_s, f.line_hz)
                                     : std::numeric_limits<double>::quiet_NaN();
  return f;
}

}  // namespace rig::monitor
