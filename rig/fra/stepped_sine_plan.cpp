#include "rig/fra/stepped_sine_plan.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rig::fra {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("sweep plan: " + what);
}

void check(const SweepPlanOptions& o) {
  require(o.dt_s > 0.0, "dt_s must be > 0");
  require(o.points >= 1, "points must be >= 1");
  require(o.f_start_hz > 0.0, "f_start_hz must be > 0");
  require(o.f_stop_hz >= o.f_start_hz, "f_stop_hz must be >= f_start_hz");
  require(o.f_stop_hz < 0.4 / o.dt_s,
          "f_stop_hz must be below 0.4 / dt_s (" + std::to_string(0.4 / o.dt_s) + " Hz)");
  require(o.slowest_time_constant_s >= 0.0, "slowest_time_constant_s must be >= 0");
  require(o.settle_time_constants >= 0.0, "settle_time_constants must be >= 0");
  require(o.min_settle_cycles >= 1, "min_settle_cycles must be >= 1");
  require(o.min_integrate_cycles >= 1, "min_integrate_cycles must be >= 1");
  require(o.ramp_cycles >= 0.0 && o.ramp_cycles <= o.min_settle_cycles,
          "ramp_cycles must be in [0, min_settle_cycles]");
  require(o.noise_rms_kw >= 0.0, "noise_rms_kw must be >= 0");
  require(o.target_rel_std >= 0.0, "target_rel_std must be >= 0");
  require(o.max_integrate_s >= 0.0, "max_integrate_s must be >= 0");
}

// Integration time of the noise rule: N dt = 2 sigma^2 dt / (r^2 |Y|^2), |Y| = A |G(f)|,
// at least min_integrate_s and at most max_integrate_s (when set).
double integrate_time_s(const SweepPlanOptions& o, double response_kw) {
  if (!(o.noise_rms_kw > 0.0) || !(o.target_rel_std > 0.0) || !(response_kw > 0.0)) {
    return o.min_integrate_s;
  }
  const double r_y = o.target_rel_std * response_kw;
  double t_s = 2.0 * o.noise_rms_kw * o.noise_rms_kw * o.dt_s / (r_y * r_y);
  if (o.max_integrate_s > 0.0) t_s = std::min(t_s, o.max_integrate_s);
  return std::max(o.min_integrate_s, t_s);
}

// Largest prior gain within f (1 +- spread), sampled on a log grid.
double max_gain_near(const ResponseFn& prior, double freq_hz, double spread) {
  constexpr int kSamples = 9;
  double g = std::abs(prior(freq_hz));
  const double lo = freq_hz / (1.0 + spread), hi = freq_hz * (1.0 + spread);
  for (double f : log_grid_hz(lo, hi, kSamples)) g = std::max(g, std::abs(prior(f)));
  return g;
}

}  // namespace

Eigen::Index SweepPlan::total_samples() const {
  Eigen::Index n = 0;
  for (const auto& p : points) n += p.total_samples();
  return n;
}

std::vector<double> log_grid_hz(double f_start_hz, double f_stop_hz, int points) {
  std::vector<double> f;
  if (points == 1) return {f_start_hz};
  const double step = std::log(f_stop_hz / f_start_hz) / (points - 1);
  for (int i = 0; i < points; ++i) f.push_back(f_start_hz * std::exp(step * i));
  f.back() = f_stop_hz;
  return f;
}

double sine_amplitude_pct(const ResponseFn& prior, double freq_hz, const AmplitudeLimits& l) {
  require(static_cast<bool>(prior), "a prior model response is required for the amplitude");
  require(l.band_kw > 0.0, "amplitude.band_kw must be > 0");
  require(l.prior_margin >= 1.0, "amplitude.prior_margin must be >= 1");
  require(l.plan_fraction > 0.0 && l.plan_fraction <= 1.0,
          "amplitude.plan_fraction must be in (0, 1]");
  require(l.max_amplitude_pct > 0.0, "amplitude.max_amplitude_pct must be > 0");
  const double headroom_kw = l.plan_fraction * l.band_kw - l.noise_peak_kw;
  require(headroom_kw > 0.0, "noise peak " + std::to_string(l.noise_peak_kw) +
                                 " kW leaves no room in the planned band of " +
                                 std::to_string(l.plan_fraction * l.band_kw) + " kW");
  const double g = max_gain_near(prior, freq_hz, l.prior_spread);
  require(std::isfinite(g), "prior gain is not finite at " + std::to_string(freq_hz) + " Hz");
  if (g <= 0.0) return l.max_amplitude_pct;
  return std::min(l.max_amplitude_pct, headroom_kw / (l.prior_margin * g));
}

SweepPlan make_sweep_plan(const SweepPlanOptions& o, const ResponseFn& prior) {
  check(o);
  SweepPlan plan;
  plan.dt_s = o.dt_s;
  for (double f : log_grid_hz(o.f_start_hz, o.f_stop_hz, o.points)) {
    SweepPoint p;
    p.freq_hz = f;
    p.amplitude_pct = sine_amplitude_pct(prior, f, o.amplitude);
    p.predicted_peak_kw = p.amplitude_pct * std::abs(prior(f)) + o.amplitude.noise_peak_kw;
    const double settle_cycles = o.settle_time_constants * o.slowest_time_constant_s * f;
    p.settle_cycles = std::max(o.min_settle_cycles, static_cast<int>(std::ceil(settle_cycles)));
    const double integrate_s = integrate_time_s(o, p.amplitude_pct * std::abs(prior(f)));
    p.integrate_cycles =
        std::max(o.min_integrate_cycles, static_cast<int>(std::ceil(integrate_s * f)));
    const double samples_per_cycle = 1.0 / (f * o.dt_s);
    p.settle_samples = std::llround(p.settle_cycles * samples_per_cycle);
    p.integrate_samples = std::llround(p.integrate_cycles * samples_per_cycle);
    p.ramp_samples = std::llround(o.ramp_cycles * samples_per_cycle);
    plan.points.push_back(p);
  }
  return plan;
}

}  // namespace rig::fra
