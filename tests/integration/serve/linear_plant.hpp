// A small linear plant for exercising the servers without the full generator-set model:
// bias-to-power is the second-order system
//   dP/dt = v,  dv/dt = wn^2 (K b - dP) - 2 zeta wn v      (P in % of rated, b bias in %)
// stepped with the exact zero-order-hold discretisation (matrix exponential of the 2x2
// system, computed once), plus seeded Gaussian measurement noise so that lockstep runs can
// show that a seed fixes every byte.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <random>

#include "plantsim/plant/plant.hpp"

namespace plantsim::testing {

struct LinearPlantOptions {
  double rated_power_w = 4.6e6;
  double operating_power_w = 3.5e6;
  double gain = 1.0;  // K, % power per % bias
  double fn_hz = 2.0;
  double zeta = 0.1;
  double noise_w = 500.0;  // standard deviation of the measurement noise
  double bias_limit_pct = Plant::kDefaultExternalBiasLimitPct;  // the governor's clamp
  std::uint64_t seed = 1;
  std::chrono::nanoseconds tick = std::chrono::milliseconds(1);
};

class LinearPlant final : public Plant {
 public:
  explicit LinearPlant(const LinearPlantOptions& options);
  void set_bias_pct(double bias_pct) override { bias_pct_ = bias_pct; }
  void step() override;
  Measurement measure() const override { return measurement_; }
  std::chrono::nanoseconds tick() const override { return options_.tick; }
  std::uint64_t ticks() const override { return ticks_; }
  double rated_power_w() const override { return options_.rated_power_w; }
  double external_bias_limit_pct() const override { return options_.bias_limit_pct; }

 private:
  void update_measurement();

  LinearPlantOptions options_;
  std::array<double, 4> phi_{};    // state transition over one tick
  std::array<double, 2> gamma_{};  // input gain over one tick (zero-order hold)
  double dp_pct_ = 0.0;
  double v_pct_s_ = 0.0;
  double bias_pct_ = 0.0;
  std::uint64_t ticks_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  Measurement measurement_;
};

// make_plant() for the linear plant: honours tick and seed; preset "linear" only.
std::unique_ptr<Plant> make_linear_plant(const PlantOptions& options);

}  // namespace plantsim::testing
