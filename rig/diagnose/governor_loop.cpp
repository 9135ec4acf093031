#include "rig/diagnose/governor_loop.hpp"

#include <algorithm>
#include <cmath>

#include "rig/diagnose/blocks.hpp"

namespace rig::diagnose {
namespace {

// a - b (highest power first, aligned at the constant term).
Eigen::VectorXd poly_subtract(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::Index n = std::max(a.size(), b.size());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  out.tail(a.size()) += a;
  out.tail(b.size()) -= b;
  return out;
}

}  // namespace

bool governor_loop_possible(const model::TransferFunction& tf) {
  const double g0 = tf.dc_gain();
  return std::isfinite(g0) && std::abs(g0) > 1e-12;
}

model::TransferFunction close_governor_loop(const model::TransferFunction& tf,
                                            const Eigen::VectorXd& nf, const Eigen::VectorXd& df,
                                            std::span<const double> place_params) {
  const double a = place_params[0], b = place_params[1], t_h = place_params[2];
  const Eigen::VectorXd nh = Eigen::Vector2d(b * t_h, a), dh = Eigen::Vector2d(t_h, 1.0);
  const double g0 = tf.dc_gain();
  model::TransferFunction out = tf;
  out.num = g0 * poly_multiply(tf.num, poly_multiply(nf, dh));
  out.den = poly_subtract(g0 * poly_multiply(tf.den, poly_multiply(df, dh)),
                          poly_multiply(tf.num, poly_multiply(nh, poly_subtract(df, nf))));
  return out;
}

void pade_delay(double tau_s, Eigen::VectorXd& num, Eigen::VectorXd& den) {
  const double t = std::max(0.0, tau_s);
  if (t < 1e-6) {
    num = den = Eigen::VectorXd::Ones(1);
    return;
  }
  // e^{-s t} ~ (1 - s t/2 + (s t)^2/10 - (s t)^3/120) / (1 + s t/2 + (s t)^2/10 + (s t)^3/120)
  const double c3 = t * t * t / 120.0, c2 = t * t / 10.0, c1 = t / 2.0;
  num = Eigen::Vector4d(-c3, c2, -c1, 1.0);
  den = Eigen::Vector4d(c3, c2, c1, 1.0);
}

}  // namespace rig::diagnose
