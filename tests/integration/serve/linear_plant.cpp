#include "tests/integration/serve/linear_plant.hpp"

#include <fmt/format.h>

#include <cmath>

namespace plantsim::testing {

// Zero-order-hold discretisation of x' = A x + B u with A = [0 1; -wn^2 -2 zeta wn],
// B = [0; wn^2 K]. Phi = exp(A T) by a truncated Taylor series on T/2^s and s squarings
// (T wn << 1, so 12 terms are exact to rounding); Gamma = A^-1 (Phi - I) B.
LinearPlant::LinearPlant(const LinearPlantOptions& o) : options_(o), rng_(o.seed) {
  const double wn = 2.0 * M_PI * o.fn_hz;
  const double t = std::chrono::duration<double>(o.tick).count();
  const std::array<double, 4> a{0.0, 1.0, -wn * wn, -2.0 * o.zeta * wn};
  auto mul = [](const std::array<double, 4>& x, const std::array<double, 4>& y) {
    return std::array<double, 4>{x[0] * y[0] + x[1] * y[2], x[0] * y[1] + x[1] * y[3],
                                 x[2] * y[0] + x[3] * y[2], x[2] * y[1] + x[3] * y[3]};
  };
  constexpr int kSquarings = 8;
  const double h = t / std::pow(2.0, kSquarings);
  std::array<double, 4> ah{a[0] * h, a[1] * h, a[2] * h, a[3] * h};
  std::array<double, 4> phi{1, 0, 0, 1}, term{1, 0, 0, 1};
  for (int k = 1; k <= 12; ++k) {
    term = mul(term, ah);
    for (int i = 0; i < 4; ++i) term[i] /= k;
    for (int i = 0; i < 4; ++i) phi[i] += term[i];
  }
  for (int s = 0; s < kSquarings; ++s) phi = mul(phi, phi);
  phi_ = phi;
  // A^-1 = 1/det [a3 -a1; -a2 a0], det = a0 a3 - a1 a2 = wn^2.
  const double det = a[0] * a[3] - a[1] * a[2];
  const std::array<double, 4> ainv{a[3] / det, -a[1] / det, -a[2] / det, a[0] / det};
  const double b1 = wn * wn * o.gain;
  const std::array<double, 2> pb{phi[1] * b1, (phi[3] - 1.0) * b1};  // (Phi - I) B
  gamma_ = {ainv[0] * pb[0] + ainv[1] * pb[1], ainv[2] * pb[0] + ainv[3] * pb[1]};
  update_measurement();
}

void LinearPlant::step() {
  const double p = phi_[0] * dp_pct_ + phi_[1] * v_pct_s_ + gamma_[0] * bias_pct_;
  const double v = phi_[2] * dp_pct_ + phi_[3] * v_pct_s_ + gamma_[1] * bias_pct_;
  dp_pct_ = p;
  v_pct_s_ = v;
  ++ticks_;
  update_measurement();
}

void LinearPlant::update_measurement() {
  auto& m = measurement_;
  m.time_s = std::chrono::duration<double>(options_.tick).count() * static_cast<double>(ticks_);
  m.power_w = options_.operating_power_w + dp_pct_ / 100.0 * options_.rated_power_w +
              options_.noise_w * noise_(rng_);
  m.speed_rpm = 600.0;
  m.freq_hz = 50.0;
  m.voltage_v = 11000.0;
  m.bias_applied_pct = bias_pct_;
}

std::unique_ptr<Plant> make_linear_plant(const PlantOptions& options) {
  if (options.config) {
    throw ConfigError(
        fmt::format("{}: the linear test plant takes no config file", options.config->string()));
  }
  if (options.preset != "linear" && options.preset != "stornoway") {
    throw ConfigError(
        fmt::format("--preset '{}': unknown preset (expected linear)", options.preset));
  }
  LinearPlantOptions o;
  o.seed = options.seed;
  o.tick = options.tick;
  return std::make_unique<LinearPlant>(o);
}

}  // namespace plantsim::testing
