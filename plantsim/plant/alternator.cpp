#include "plantsim/plant/alternator.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "plantsim/plant/plant.hpp"

namespace plantsim {

void Alternator::init(double pe0_pu, double* x) {
  const double e = p_[P::kAltE], v = p_[P::kGridV], xt = reactance_pu();
  const double sin_d = pe0_pu * xt / (e * v);
  if (grid() && sin_d >= 0.95) {
    throw ConfigError(fmt::format(
        "op.power_kw: {} kW needs sin(delta) = {:.2f} through X = {} pu; expected < 0.95 "
        "(lower the power or raise alt.e_pu)",
        p_[P::kPowerKw], sin_d, xt));
  }
  x[kDw] = 0.0;
  x[kDelta] = grid() ? std::asin(sin_d) : 0.0;
  x[kEq] = e;
  const double id = grid() ? (e - v * std::cos(x[kDelta])) / xt : 0.0;
  efd0_pu_ = e + (p_[P::kAltXd] - p_[P::kAltXdp]) * id;
  x[kEfd] = efd0_pu_;
  load0_pu_ = pe0_pu;
  vref_pu_ = terminal_voltage_pu(x) + efd0_pu_ / p_[P::kAltAvrKa];
}

double Alternator::electrical_power_pu(const double* x) const {
  if (grid()) return x[kEq] * p_[P::kGridV] * std::sin(x[kDelta]) / reactance_pu();
  const double load = load0_pu_ + p_[P::kLoadPu];
  return load * (1.0 + p_[P::kLoadD] * x[kDw]);
}

double Alternator::terminal_voltage_pu(const double* x) const {
  if (!grid()) return x[kEq];
  // Vt = V + j xe I with I = (E' e^{j delta} - V) / (j X): the point xe/X along the chord.
  const std::complex<double> e = std::polar(x[kEq], x[kDelta]);
  const std::complex<double> v{p_[P::kGridV], 0.0};
  return std::abs(v + (p_[P::kGridXe] / reactance_pu()) * (e - v));
}

void Alternator::derivatives(const double* x, double torque_pu, double* dx) const {
  const double w = 1.0 + x[kDw];
  const double pe = electrical_power_pu(x);
  dx[kDw] = (torque_pu - pe / w - p_[P::kAltD] * x[kDw]) / (2.0 * p_[P::kAltH]);
  dx[kDelta] = 2.0 * std::numbers::pi * p_[P::kFreqHz] * x[kDw];
  dx[kEq] = 0.0;
  dx[kEfd] = 0.0;
  if (p_[P::kAltFluxDecay] > 0.5) {
    const double id =
        grid() ? (x[kEq] - p_[P::kGridV] * std::cos(x[kDelta])) / reactance_pu() : 0.0;
    dx[kEq] = (x[kEfd] - x[kEq] - (p_[P::kAltXd] - p_[P::kAltXdp]) * id) / p_[P::kAltTdo];
    if (p_[P::kAltAvr] > 0.5) {
      const double vt = terminal_voltage_pu(x);
      dx[kEfd] = (p_[P::kAltAvrKa] * (vref_pu_ - vt) - x[kEfd]) / p_[P::kAltAvrTa];
    }
  }
}

std::complex<double> Alternator::torque_to_power(const double* x, std::complex<double> s) const {
  // Linearised swing: 2H s dw = dTm - dPe + Pe0 dw - D dw; grid dPe = Ks w_b dw / s,
  // island dPe = P_L0 D_L dw.
  const double h = p_[P::kAltH];
  const double pe0 = electrical_power_pu(x);
  const double d = p_[P::kAltD] - pe0;
  if (grid()) {
    const double ks = x[kEq] * p_[P::kGridV] * std::cos(x[kDelta]) / reactance_pu();
    const double kw = ks * 2.0 * std::numbers::pi * p_[P::kFreqHz];
    return kw / (2.0 * h * s * s + d * s + kw);
  }
  const double kl = (load0_pu_ + p_[P::kLoadPu]) * p_[P::kLoadD];
  return kl / (2.0 * h * s + d + kl);
}

}  // namespace plantsim
