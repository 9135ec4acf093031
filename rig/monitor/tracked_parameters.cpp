#include "rig/monitor/tracked_parameters.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace rig::monitor {
namespace {

using Poly = Eigen::VectorXd;

// Real polynomial (highest power first) with the given roots (complex ones in conjugate pairs).
Poly poly_from_roots(const Eigen::VectorXcd& roots) {
  Eigen::VectorXcd p = Eigen::VectorXcd::Ones(1);
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    Eigen::VectorXcd q = Eigen::VectorXcd::Zero(p.size() + 1);
    q.head(p.size()) = p;
    q.tail(p.size()) -= roots(i) * p;
    p = q;
  }
  return p.real();
}

// Moves the dominant pair to (wn_scale wn, zeta_scale zeta), keeping the DC gain.
model::TransferFunction move_pair(const model::TransferFunction& base, double wn_scale,
                                  double zeta_scale) {
  const int i = dominant_pair(base);
  if (i < 0) return base;
  Eigen::VectorXcd poles = base.poles();
  const std::complex<double> p = poles(i);
  const double wn = std::abs(p);
  const double zeta = -p.real() / wn;
  const double wn2 = wn * wn_scale;
  const double zeta2 = std::clamp(zeta * zeta_scale, 1e-4, 0.9999);
  const std::complex<double> moved(-zeta2 * wn2, wn2 * std::sqrt(1.0 - zeta2 * zeta2));
  for (Eigen::Index k = 0; k < poles.size(); ++k) {
    if (std::abs(poles(k) - p) < 1e-9 * wn) poles(k) = moved;
    if (std::abs(poles(k) - std::conj(p)) < 1e-9 * wn) poles(k) = std::conj(moved);
  }
  model::TransferFunction tf = model::monic(base);
  const double dc_before = tf.dc_gain();
  tf.den = poly_from_roots(poles);
  const double dc_after = tf.num(tf.num.size() - 1) / tf.den(tf.den.size() - 1);
  if (std::isfinite(dc_before) && std::isfinite(dc_after) && dc_after != 0.0) {
    tf.num *= dc_before / dc_after;
  }
  return tf;
}

model::TransferFunction deform_gain(const model::TransferFunction& b, double d) {
  model::TransferFunction tf = b;
  tf.num *= 1.0 + d;
  return tf;
}
model::TransferFunction deform_damping(const model::TransferFunction& b, double d) {
  return move_pair(b, 1.0, 1.0 + d);
}
model::TransferFunction deform_frequency(const model::TransferFunction& b, double d) {
  return move_pair(b, 1.0 + d, 1.0);
}
model::TransferFunction deform_delay(const model::TransferFunction& b, double d) {
  model::TransferFunction tf = b;
  tf.delay_s = std::max(0.0, tf.delay_s + d);
  return tf;
}

double to_db(double d) { return 20.0 * std::log10(std::max(1e-6, 1.0 + d)); }
double to_pct(double d) { return 100.0 * d; }
double to_ms(double d) { return 1000.0 * d; }

}  // namespace

const std::vector<TrackedParameter>& tracked_parameters() {
  static const std::vector<TrackedParameter> table = {
      {"gain", "dB", 0.02, deform_gain, to_db},
      {"damping", "%", 0.05, deform_damping, to_pct},
      {"frequency", "%", 0.01, deform_frequency, to_pct},
      {"delay", "ms", 0.005, deform_delay, to_ms},
  };
  return table;
}

int dominant_pair(const model::TransferFunction& tf) {
  const Eigen::VectorXcd poles = tf.poles();
  int best = -1;
  double best_zeta = 2.0;
  for (Eigen::Index k = 0; k < poles.size(); ++k) {
    const std::complex<double> p = poles(k);
    if (p.imag() <= 1e-9 * std::abs(p)) continue;
    const double zeta = -p.real() / std::abs(p);
    if (zeta < best_zeta) {
      best_zeta = zeta;
      best = static_cast<int>(k);
    }
  }
  return best;
}

ModeFigures dominant_mode(const model::TransferFunction& tf) {
  const int i = dominant_pair(tf);
  if (i < 0) return {};
  const std::complex<double> p = tf.poles()(i);
  return {std::abs(p) / (2.0 * std::numbers::pi), -p.real() / std::abs(p)};
}

}  // namespace rig::monitor
