// Steady-state check before excitation (DESIGN.md section 8): the set must hold a steady
// power P0 with noise and drift within bounds, otherwise the test refuses to start.
#pragma once

#include <string>
#include <vector>

namespace rig::session {

struct SteadyStateLimits {
  double max_noise_pct = 0.5;  // std of the detrended power, % of P0
  double max_drift_pct = 0.5;  // |slope| * duration, % of P0
  double min_power_kw = 1.0;
};

struct SteadyStateResult {
  bool ok = false;
  double p0_kw = 0.0;       // mean power over the record
  double noise_pct = 0.0;   // std(P - linear trend) / P0 * 100
  double drift_pct = 0.0;   // |trend slope| * duration / P0 * 100
  double duration_s = 0.0;
  std::size_t samples = 0;
  std::string reason;       // why it failed, one line (empty when ok)
};

// Fits P(t) = a + b t by least squares; noise is the residual standard deviation and drift
// the fitted change over the record, |b| T. Non-finite samples fail the check.
SteadyStateResult check_steady_state(const std::vector<double>& t_s,
                                     const std::vector<double>& power_kw,
                                     const SteadyStateLimits& limits);

}  // namespace rig::session
