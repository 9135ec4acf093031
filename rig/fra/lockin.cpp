#include "rig/fra/lockin.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rig::fra {

double HarmonicFit::fundamental_power() const { return 0.5 * std::norm(harmonics.front()); }

double HarmonicFit::distortion() const {
  double p = 0.0;
  for (std::size_t k = 1; k < harmonics.size(); ++k) p += std::norm(harmonics[k]);
  return p / std::norm(harmonics.front());
}

double HarmonicFit::noise_ratio() const { return residual_var / fundamental_power(); }

double HarmonicFit::relative_variance() const {
  return 4.0 * residual_var / (static_cast<double>(samples) * std::norm(harmonics.front()));
}

HarmonicFit fit_harmonics(const Eigen::VectorXd& x, double freq_hz, double dt_s, double t0_s,
                          int max_harmonic) {
  if (!(freq_hz > 0.0) || !(dt_s > 0.0) || max_harmonic < 1) {
    throw std::invalid_argument("fit_harmonics: expected freq_hz > 0, dt_s > 0, max_harmonic >= 1");
  }
  int harmonics = 1;
  while (harmonics < max_harmonic && (harmonics + 1) * freq_hz < 0.45 / dt_s) ++harmonics;
  const Eigen::Index n = x.size();
  const Eigen::Index cols = 2 + 2 * harmonics;
  if (n < 2 * cols) {
    throw std::invalid_argument("fit_harmonics: record of " + std::to_string(n) +
                                " samples is too short (need " + std::to_string(2 * cols) + ")");
  }
  const double w = 2.0 * std::numbers::pi * freq_hz;
  const double t_mid = t0_s + 0.5 * static_cast<double>(n - 1) * dt_s;
  Eigen::MatrixXd a(n, cols);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = t0_s + static_cast<double>(i) * dt_s;
    a(i, 0) = 1.0;
    a(i, 1) = t - t_mid;
    for (int k = 1; k <= harmonics; ++k) {
      a(i, 2 * k) = std::cos(k * w * t);
      a(i, 2 * k + 1) = std::sin(k * w * t);
    }
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(x);
  const Eigen::VectorXd residual = x - a * c;
  HarmonicFit fit;
  fit.mean = c(0);
  fit.drift_per_s = c(1);
  fit.samples = n;
  fit.residual_var = residual.squaredNorm() / static_cast<double>(n - cols);
  for (int k = 1; k <= harmonics; ++k) fit.harmonics.emplace_back(c(2 * k), -c(2 * k + 1));
  return fit;
}

LockInPoint lock_in(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double freq_hz, double dt_s,
                    double t0_s, int max_harmonic) {
  if (u.size() != y.size()) {
    throw std::invalid_argument("lock_in: u and y differ in length (" + std::to_string(u.size()) +
                                " vs " + std::to_string(y.size()) + ")");
  }
  LockInPoint p;
  p.freq_hz = freq_hz;
  p.u = fit_harmonics(u, freq_hz, dt_s, t0_s, max_harmonic);
  p.y = fit_harmonics(y, freq_hz, dt_s, t0_s, max_harmonic);
  p.ratio = p.y.fundamental() / p.u.fundamental();
  const double rv_u = p.u.relative_variance();
  const double rv_y = p.y.relative_variance();
  p.coherence = 1.0 / ((1.0 + rv_u) * (1.0 + rv_y));
  const double rel_std = std::sqrt(0.5 * (rv_u + rv_y));
  p.mag_std_db = 20.0 / std::log(10.0) * rel_std;
  p.phase_std_deg = rel_std * 180.0 / std::numbers::pi;
  return p;
}

}  // namespace rig::fra
