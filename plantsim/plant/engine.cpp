#include "plantsim/plant/engine.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace plantsim {

double dead_time_s(const Params& p) {
  if (p[P::kEngDeadTime] > 0.0) return p[P::kEngDeadTime];
  const double n_rpm = p[P::kEngRpm];
  return 30.0 / n_rpm + 60.0 / (p[P::kEngCylinders] * n_rpm);
}

double cylinder_factor(const Params& p) {
  const int n = static_cast<int>(std::lround(p[P::kEngCylinders]));
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += p.injector(k);
  return sum / n;
}

double map_fuel_limit_pu(const Params& p, double boost_pu) {
  return p[P::kEngMapMin] + p[P::kEngMapGain] * boost_pu;
}

double Engine::init(double tm0_pu, double* x) const {
  x[kTorque] = tm0_pu;
  x[kBoost] = tm0_pu;
  const double c = cylinder_factor(p_);
  return c > 0.0 ? tm0_pu / c : 0.0;
}

void Engine::derivatives(const double* x, double fuel_delayed_pu, double* dx) const {
  const double limit = map_fuel_limit_pu(p_, x[kBoost]);
  const double fuel = std::clamp(fuel_delayed_pu, 0.0, std::max(limit, 0.0));
  const double delivered = cylinder_factor(p_) * fuel;
  dx[kTorque] = (delivered - x[kTorque]) / p_[P::kEngCombustionLag];
  dx[kBoost] = (delivered - x[kBoost]) / p_[P::kEngBoostLag];
}

FuelDelayLine::FuelDelayLine(double dt_s, double max_delay_s, double initial_pu)
    : dt_s_(dt_s), ring_(static_cast<std::size_t>(std::ceil(max_delay_s / dt_s)) + 4, initial_pu) {}

void FuelDelayLine::push(double t_s, double rack_pu) {
  head_ = (head_ + 1) % ring_.size();
  ring_[head_] = rack_pu;
  t_newest_s_ = t_s;
}

double FuelDelayLine::at(double t_s) const {
  // Samples lie at t_newest - i dt (i = 0 .. size-1); before the start the initial value
  // fills the ring, which is the steady state the plant was initialised in.
  const double back = (t_newest_s_ - t_s) / dt_s_;
  if (back <= 0.0) return ring_[head_];
  const double max_back = static_cast<double>(ring_.size() - 2);
  const double b = std::min(back, max_back);
  const auto i = static_cast<std::size_t>(b);
  const double frac = b - static_cast<double>(i);
  const std::size_t n = ring_.size();
  const double newer = ring_[(head_ + n - i) % n];
  const double older = ring_[(head_ + n - i - 1) % n];
  return newer + frac * (older - newer);
}

void FiringRipple::set_weights(const Params& p) {
  const int n = static_cast<int>(std::lround(p[P::kEngCylinders]));
  // Health with injectors_out folded in (a fractional value cuts part of one cylinder).
  std::array<double, kMaxCylinders> health{};
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += health[static_cast<std::size_t>(k)] = p.injector(k);
  enabled_ = p[P::kEngRipple] > 0.5 && sum > 0.0;
  cycle_rad_s_ = 2.0 * std::numbers::pi * p[P::kEngRpm] / 120.0;
  // Pulse width in cycle radians (720 crank degrees per cycle), Gaussian sigma = width / 2.
  const double sigma_rad = 0.5 * p[P::kEngPulseWidth] * std::numbers::pi / 360.0;
  const int harmonics = 2 * n;
  weights_.assign(static_cast<std::size_t>(harmonics), {0.0, 0.0});
  if (!enabled_) return;
  // Equal firing intervals phi_k = 2 pi k / n: e^{-j h phi_k} is the (h k mod n)-th root.
  std::array<std::complex<double>, kMaxCylinders> roots{};
  for (int m = 0; m < n; ++m) {
    roots[static_cast<std::size_t>(m)] = std::polar(1.0, -2.0 * std::numbers::pi * m / n);
  }
  for (int h = 1; h <= harmonics; ++h) {
    const double c_h = std::exp(-0.5 * (h * sigma_rad) * (h * sigma_rad));
    std::complex<double> s{0.0, 0.0};
    for (int k = 0; k < n; ++k) {
      s += health[static_cast<std::size_t>(k)] * roots[static_cast<std::size_t>((h * k) % n)];
    }
    weights_[static_cast<std::size_t>(h - 1)] = 2.0 * c_h / sum * s;
  }
}

double FiringRipple::advance(double dt_s, double w_pu, double torque_pu) {
  phase_rad_ = std::fmod(phase_rad_ + cycle_rad_s_ * w_pu * dt_s, 2.0 * std::numbers::pi);
  if (!enabled_) return 0.0;
  double sum = 0.0;
  for (int h : active_) {
    sum += (gains_[static_cast<std::size_t>(h - 1)] * std::polar(1.0, h * phase_rad_)).real();
  }
  return torque_pu * sum;
}

}  // namespace plantsim
