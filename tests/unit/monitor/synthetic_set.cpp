#include "synthetic_set.hpp"

#include <cmath>
#include <numbers>
#include <random>

namespace rig::monitor::testing {

model::TransferFunction sopdt(double gain, double fn_hz, double zeta, double delay_s) {
  const double wn = 2.0 * std::numbers::pi * fn_hz;
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, gain * wn * wn);
  tf.den = Eigen::Vector3d(1.0, 2.0 * zeta * wn, wn * wn);
  tf.delay_s = delay_s;
  return tf;
}

SyntheticRecord generate(const SyntheticSet& set, const model::TransferFunction& g,
                         double duration_s, const SyntheticChange& change) {
  const auto n = static_cast<Eigen::Index>(std::lround(duration_s / set.dt_s));
  std::mt19937_64 rng(set.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  // Gaussian excitation low-passed at ~6 Hz (first order), scaled to sigma_pct.
  Eigen::VectorXd u(n);
  const double a = std::exp(-2.0 * std::numbers::pi * 6.0 * set.dt_s);
  const double gain = set.sigma_pct * std::sqrt((1.0 + a) / (1.0 - a));
  double state = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    state = a * state + (1.0 - a) * normal(rng);
    u(k) = gain * state;
  }
  const Eigen::VectorXd y0 = model::simulate(g, u, set.dt_s);
  const Eigen::VectorXd y1 = change.model ? model::simulate(*change.model, u, set.dt_s) : y0;
  SyntheticRecord r;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * set.dt_s;
    const bool after = t >= change.at_s;
    double y = set.p0_kw + (after ? y1(k) : y0(k)) + set.noise_kw * normal(rng);
    if (after) {
      y += change.level_step_kw +
           change.line_kw * std::sin(2.0 * std::numbers::pi * set.speed_rpm / 120.0 * t);
    }
    r.t_s.push_back(t);
    r.u_pct.push_back(u(k));
    r.y_kw.push_back(y);
  }
  return r;
}

}  // namespace rig::monitor::testing
