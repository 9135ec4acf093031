#include "rig/signal/butterworth.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rig::signal {

ButterworthLowPass::ButterworthLowPass(int order, double corner_hz, double dt_s) : dt_s_(dt_s) {
  if (order < 1 || order > 8) {
    throw std::invalid_argument("Butterworth: order must be 1..8, got " + std::to_string(order));
  }
  if (!(dt_s > 0.0) || !(corner_hz > 0.0) || !(corner_hz < 0.5 / dt_s)) {
    throw std::invalid_argument(
        "Butterworth: need dt_s > 0 and 0 < corner_hz < Nyquist, got "
        "corner_hz=" +
        std::to_string(corner_hz) + " dt_s=" + std::to_string(dt_s));
  }
  const double k = 2.0 / dt_s;
  const double wc = k * std::tan(std::numbers::pi * corner_hz * dt_s);
  const double wc2 = wc * wc;
  for (int p = 1; p <= order / 2; ++p) {
    // wc^2 / (s^2 + 2 zeta wc s + wc^2) under s = k (1 - z^-1)/(1 + z^-1).
    const double zeta = std::sin(std::numbers::pi * (2.0 * p - 1.0) / (2.0 * order));
    const double a0 = k * k + 2.0 * zeta * wc * k + wc2;
    sections_.push_back({wc2 / a0, 2.0 * wc2 / a0, wc2 / a0, (2.0 * wc2 - 2.0 * k * k) / a0,
                         (k * k - 2.0 * zeta * wc * k + wc2) / a0});
  }
  if (order % 2 == 1) {
    // wc / (s + wc) -> wc (1 + z^-1) / ((k + wc) + (wc - k) z^-1).
    const double a0 = k + wc;
    sections_.push_back({wc / a0, wc / a0, 0.0, (wc - k) / a0, 0.0});
  }
}

double ButterworthLowPass::step(double x) {
  for (auto& s : sections_) {
    const double y = s.b0 * x + s.s1;
    s.s1 = s.b1 * x - s.a1 * y + s.s2;
    s.s2 = s.b2 * x - s.a2 * y;
    x = y;
  }
  return x;
}

Eigen::VectorXd ButterworthLowPass::process(const Eigen::VectorXd& x) {
  Eigen::VectorXd y(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) y[i] = step(x[i]);
  return y;
}

void ButterworthLowPass::reset() {
  for (auto& s : sections_) s.s1 = s.s2 = 0.0;
}

std::complex<double> ButterworthLowPass::response(double freq_hz) const {
  const std::complex<double> zi = std::polar(1.0, -2.0 * std::numbers::pi * freq_hz * dt_s_);
  std::complex<double> h = 1.0;
  for (const auto& s : sections_) {
    h *= (s.b0 + zi * (s.b1 + zi * s.b2)) / (1.0 + zi * (s.a1 + zi * s.a2));
  }
  return h;
}

}  // namespace rig::signal
