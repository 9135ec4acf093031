#include "rig/signal/ac_coupling.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rig::signal {

AcCoupler::AcCoupler(double dt_s, double rc_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("AC coupler: dt_s must be > 0, got " + std::to_string(dt_s));
  }
  if (!(rc_s > 0.0) || !std::isfinite(rc_s)) {
    throw std::invalid_argument("AC coupler: rc_s must be > 0, got " + std::to_string(rc_s));
  }
  a_ = std::exp(-dt_s / rc_s);
}

Eigen::VectorXd AcCoupler::process(const Eigen::VectorXd& x) {
  // step() on locals: the state kept in registers, not reloaded past each store to v.
  Eigen::VectorXd v(x.size());
  const double a = a_;
  double x_prev = x_prev_, out = v_;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    out = a * out + x[i] - x_prev;
    x_prev = x[i];
    v[i] = out;
  }
  x_prev_ = x_prev, v_ = out;
  return v;
}

Eigen::VectorXd ac_couple(const Eigen::VectorXd& x, double dt_s, double rc_s) {
  AcCoupler coupler(dt_s, rc_s);
  return coupler.process(x);
}

double rc_from_corner_hz(double corner_hz) {
  if (!(corner_hz > 0.0) || !std::isfinite(corner_hz)) {
    throw std::invalid_argument("AC coupler: corner_hz must be > 0, got " +
                                std::to_string(corner_hz));
  }
  return 1.0 / (2.0 * std::numbers::pi * corner_hz);
}

}  // namespace rig::signal
