// Test-data generator for the monitor's core: a second-order set (the Stornoway SOPDT fit,
// 46.3 kW/%, 2.03 Hz, zeta 0.10, 78 ms) driven by a Gaussian excitation, with white
// measurement noise, and a change at a given time: the model's gain, damping or delay, an
// engine-order line (a missing cylinder's half order), or a step in the measured level.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "rig/model/transfer_function.hpp"

namespace rig::monitor::testing {

model::TransferFunction sopdt(double gain_kw_per_pct = 46.3, double fn_hz = 2.03,
                              double zeta = 0.10, double delay_s = 0.078);

struct SyntheticChange {
  double at_s = 1e30;
  std::optional<model::TransferFunction> model;  // the set's model from at_s on
  double line_kw = 0.0;                          // amplitude of a 5 Hz line from at_s on
  double level_step_kw = 0.0;                    // measured level step at at_s
};

struct SyntheticSet {
  double dt_s = 0.01;
  double p0_kw = 3500.0;
  double sigma_pct = 0.18;  // a +-1 % band at 4 sigma for the Stornoway gain
  double noise_kw = 5.0;
  double speed_rpm = 600.0;
  std::uint64_t seed = 1;
};

struct SyntheticRecord {
  std::vector<double> t_s, u_pct, y_kw;
};

// duration_s of samples; the model switch is exact (two simulations spliced at at_s, the
// second over the whole record so that its state is continuous).
SyntheticRecord generate(const SyntheticSet& set, const model::TransferFunction& g,
                         double duration_s, const SyntheticChange& change = {});

}  // namespace rig::monitor::testing
