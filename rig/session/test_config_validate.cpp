// Cross-field rules of the test file: what makes a test unsafe or meaningless is refused here,
// before the link is even opened.
#include <fmt/format.h>

#include <cmath>
#include <string>

#include "rig/session/test_config.hpp"

namespace rig::session {
namespace {

struct Checker {
  const std::string& source;

  void require(bool ok, const std::string& key, double value, const std::string& what) const {
    if (!ok) throw ConfigError(fmt::format("{}: {} = {}: {}", source, key, value, what));
  }
  void positive(const std::string& key, double value) const {
    require(value > 0.0, key, value, "must be greater than 0");
  }
  void at_least(const std::string& key, double value, double min) const {
    require(value >= min, key, value, fmt::format("must be at least {}", min));
  }
};

void check_link_and_safety(const TestConfig& c, const Checker& k) {
  k.positive("link.sample_rate_hz", c.link.sample_rate_hz);
  k.at_least("link.lockstep_ticks", c.link.lockstep_ticks, 0);
  k.require(c.link.lockstep_ticks <= 65535, "link.lockstep_ticks", c.link.lockstep_ticks,
            "must fit the 16-bit advance register (<= 65535)");
  k.positive("link.timeout_s", c.link.timeout_s);
  k.positive("plant.rated_power_kw", c.plant.rated_power_kw);
  k.positive("safety.band_pct", c.safety.band_pct);
  k.require(c.safety.band_pct <= kStandardBandPct || c.safety.allow_band_above_3pct,
            "safety.band_pct", c.safety.band_pct,
            "above 3 % of P0 needs safety.allow_band_above_3pct = true");
  k.require(c.safety.plan_fraction > 0.0 && c.safety.plan_fraction <= 1.0, "safety.plan_fraction",
            c.safety.plan_fraction, "must be in (0, 1]");
  k.require(c.safety.backoff_fraction >= c.safety.plan_fraction && c.safety.backoff_fraction <= 1.0,
            "safety.backoff_fraction", c.safety.backoff_fraction,
            "must be between safety.plan_fraction and 1");
  k.positive("safety.clamp_pct", c.safety.clamp_pct);
  k.positive("safety.ramp_pct_per_s", c.safety.ramp_pct_per_s);
  k.positive("steady_state.duration_s", c.steady_state.duration_s);
  k.positive("steady_state.max_noise_pct", c.steady_state.max_noise_pct);
  k.positive("steady_state.max_drift_pct", c.steady_state.max_drift_pct);
  k.at_least("steady_state.min_power_kw", c.steady_state.min_power_kw, 0.0);
  k.positive("pilot.amplitude_pct", c.pilot.amplitude_pct);
  k.require(c.pilot.amplitude_pct <= c.safety.clamp_pct, "pilot.amplitude_pct",
            c.pilot.amplitude_pct, "must not exceed safety.clamp_pct");
  k.positive("pilot.duration_s", c.pilot.duration_s);
}

void check_excitation_and_mmfm(const TestConfig& c, const Checker& k) {
  const double nyquist_hz = c.link.sample_rate_hz / 2.0;
  const std::string below_nyquist =
      fmt::format("must be below the Nyquist frequency {} Hz of link.sample_rate_hz = {}",
                  nyquist_hz, c.link.sample_rate_hz);
  k.positive("excitation.bandwidth_hz", c.excitation.bandwidth_hz);
  k.require(c.excitation.bandwidth_hz < nyquist_hz, "excitation.bandwidth_hz",
            c.excitation.bandwidth_hz, below_nyquist);
  k.at_least("excitation.ac_coupling_rc_s", c.excitation.ac_coupling_rc_s, 0.0);
  k.require(c.excitation.prbs_register_length >= 3 && c.excitation.prbs_register_length <= 31,
            "excitation.prbs_register_length", c.excitation.prbs_register_length,
            "must be 3 to 31");
  k.at_least("excitation.prbs_clock_divider", double(c.excitation.prbs_clock_divider), 1);
  k.at_least("mmfm.order_n", double(c.mmfm.order_n), 1);
  k.require(c.mmfm.order_m >= 0 && c.mmfm.order_m <= c.mmfm.order_n, "mmfm.order_m", c.mmfm.order_m,
            "must be between 0 and mmfm.order_n");
  if (c.mmfm.delay_s) k.at_least("mmfm.delay_s", *c.mmfm.delay_s, 0.0);
  k.at_least("mmfm.lags", double(c.mmfm.lags), 16);
  k.require(c.mmfm.block_size >= c.mmfm.lags, "mmfm.block_size", c.mmfm.block_size,
            "must be at least mmfm.lags");
  k.at_least("mmfm.skip", double(c.mmfm.skip), 1);
  k.at_least("mmfm.averaging_w", double(c.mmfm.averaging_w), 1);
  k.positive("mmfm.target_db", c.mmfm.target_db);
  k.positive("mmfm.target_deg", c.mmfm.target_deg);
  k.at_least("mmfm.min_duration_s", c.mmfm.min_duration_s, 0.0);
  k.require(c.mmfm.max_duration_s >= c.mmfm.min_duration_s && c.mmfm.max_duration_s > 0.0,
            "mmfm.max_duration_s", c.mmfm.max_duration_s,
            "must be positive and at least mmfm.min_duration_s");
  const double block_s = c.mmfm.block_size / c.link.sample_rate_hz;
  k.require(c.mmfm.max_duration_s >= block_s, "mmfm.max_duration_s", c.mmfm.max_duration_s,
            fmt::format("must hold at least one block ({} s)", block_s));
}

void check_sweep_and_compare(const TestConfig& c, const Checker& k) {
  const double nyquist_hz = c.link.sample_rate_hz / 2.0;
  const std::string below_nyquist =
      fmt::format("must be below the Nyquist frequency {} Hz of link.sample_rate_hz = {}",
                  nyquist_hz, c.link.sample_rate_hz);
  k.positive("sweep.from_hz", c.sweep.from_hz);
  k.require(c.sweep.to_hz > c.sweep.from_hz, "sweep.to_hz", c.sweep.to_hz,
            "must be above sweep.from_hz");
  k.require(c.sweep.to_hz < nyquist_hz, "sweep.to_hz", c.sweep.to_hz, below_nyquist);
  k.at_least("sweep.points", double(c.sweep.points), 2);
  k.at_least("sweep.settle_cycles", c.sweep.settle_cycles, 0.0);
  k.at_least("sweep.integrate_cycles", c.sweep.integrate_cycles, 1.0);
  k.at_least("sweep.settle_time_constants", c.sweep.settle_time_constants, 0.0);
  k.at_least("sweep.min_integrate_s", c.sweep.min_integrate_s, 0.0);
  k.positive("compare.from_hz", c.compare.from_hz);
  k.require(c.compare.to_hz > c.compare.from_hz, "compare.to_hz", c.compare.to_hz,
            "must be above compare.from_hz");
  k.require(c.compare.to_hz < nyquist_hz, "compare.to_hz", c.compare.to_hz, below_nyquist);
  k.positive("compare.mag_tol_db", c.compare.mag_tol_db);
  k.positive("compare.phase_tol_deg", c.compare.phase_tol_deg);
  k.require(c.compare.min_coherence >= 0.0 && c.compare.min_coherence <= 1.0,
            "compare.min_coherence", c.compare.min_coherence, "must be in [0, 1]");
  k.positive("output.flush_interval_s", c.output.flush_interval_s);
  k.require(c.output.flush_interval_s <= 1.0, "output.flush_interval_s", c.output.flush_interval_s,
            "must be at most 1 s (the recording must survive a kill)");
  k.positive("output.live_interval_s", c.output.live_interval_s);
}

// Every numeric key's safe range (docs/test-file.md, "Safe ranges"): the lower bounds are in
// the checks above; these are the upper ones, each with its reason.
struct UpperBound {
  const char* key;
  double value;
  double max;
  const char* why;
};

void check_upper_bounds(const TestConfig& c, const Checker& k) {
  const UpperBound bounds[] = {
      {"link.sample_rate_hz", c.link.sample_rate_hz, 1000.0,
       "one Modbus/CAN exchange per sample: no governor link keeps up above 1 kHz"},
      {"link.timeout_s", c.link.timeout_s, 10.0, "a governor silent for 10 s is gone"},
      {"plant.rated_power_kw", c.plant.rated_power_kw, 1e6, "a generator set of at most 1 GW"},
      {"safety.band_pct", c.safety.band_pct, 10.0, "even with the override"},
      {"safety.clamp_pct", c.safety.clamp_pct, 10.0,
       "an external bias above 10 % of rated is no small-signal test"},
      {"safety.ramp_pct_per_s", c.safety.ramp_pct_per_s, 10.0,
       "a faster ramp is a step to a 2 Hz electromechanical mode"},
      {"safety.activation_timeout_s", c.safety.activation_timeout_s, 10.0,
       "a governor that takes longer to accept the bias is not ready"},
      {"safety.echo_tolerance_pct", c.safety.echo_tolerance_pct, 1.0,
       "a wider tolerance would not notice a governor that ignores the bias"},
      {"safety.echo_delay_s", c.safety.echo_delay_s, 0.5, "the heartbeat period"},
      {"safety.echo_max_bad_s", c.safety.echo_max_bad_s, 0.5, "the heartbeat period"},
      {"steady_state.duration_s", c.steady_state.duration_s, 600.0, "ten minutes"},
      {"steady_state.max_noise_pct", c.steady_state.max_noise_pct, 3.0, "the standard band"},
      {"steady_state.max_drift_pct", c.steady_state.max_drift_pct, 3.0, "the standard band"},
      {"steady_state.min_power_kw", c.steady_state.min_power_kw, 1e6, "plant.rated_power_kw"},
      {"pilot.duration_s", c.pilot.duration_s, 600.0, "ten minutes"},
      {"excitation.ac_coupling_rc_s", c.excitation.ac_coupling_rc_s, 1000.0,
       "a longer RC is no coupling (use 0)"},
      {"excitation.prbs_clock_divider", double(c.excitation.prbs_clock_divider), 1000.0,
       "a slower PRBS clock excites nothing"},
      {"mmfm.order_n", double(c.mmfm.order_n), 8.0, "MMFM is conditioned up to order 8"},
      {"mmfm.lags", double(c.mmfm.lags), 8192.0, "the correlators' memory and time per block"},
      {"mmfm.block_size", double(c.mmfm.block_size), 1048576.0, "2^20 samples per block"},
      {"mmfm.skip", double(c.mmfm.skip), 64.0, "Fell's skip beyond 64 leaves too few products"},
      {"mmfm.averaging_w", double(c.mmfm.averaging_w), 1000.0, "blocks"},
      {"mmfm.target_db", c.mmfm.target_db, 20.0, "a factor of ten"},
      {"mmfm.target_deg", c.mmfm.target_deg, 90.0, "a quarter turn"},
      {"mmfm.min_duration_s", c.mmfm.min_duration_s, 86400.0, "a day"},
      {"mmfm.max_duration_s", c.mmfm.max_duration_s, 86400.0, "a day"},
      {"mmfm.min_applied_fraction", c.mmfm.min_applied_fraction, 1.0, "a share"},
      {"sweep.points", double(c.sweep.points), 200.0, "points per sweep"},
      {"sweep.settle_cycles", c.sweep.settle_cycles, 1000.0, "cycles"},
      {"sweep.integrate_cycles", c.sweep.integrate_cycles, 10000.0, "cycles"},
      {"sweep.settle_time_constants", c.sweep.settle_time_constants, 100.0, "time constants"},
      {"sweep.min_integrate_s", c.sweep.min_integrate_s, 3600.0, "an hour per point"},
      {"compare.mag_tol_db", c.compare.mag_tol_db, 20.0, "a check wider than 20 dB checks nothing"},
      {"compare.phase_tol_deg", c.compare.phase_tol_deg, 90.0, "a quarter cycle"},
      {"output.live_interval_s", c.output.live_interval_s, 3600.0, "an hour"},
  };
  for (const auto& b : bounds) {
    k.require(std::isfinite(b.value) && b.value <= b.max, b.key, b.value,
              fmt::format("must be at most {} ({})", b.max, b.why));
  }
  k.positive("safety.activation_timeout_s", c.safety.activation_timeout_s);
  k.at_least("safety.echo_tolerance_pct", c.safety.echo_tolerance_pct, 0.001);
  k.at_least("safety.echo_delay_s", c.safety.echo_delay_s, 0.0);
  k.at_least("safety.echo_max_bad_s", c.safety.echo_max_bad_s, 0.0);
  k.at_least("mmfm.min_applied_fraction", c.mmfm.min_applied_fraction, 0.0);
  k.at_least("link.sample_rate_hz", c.link.sample_rate_hz, 1.0);
}

}  // namespace

void validate(const TestConfig& config) {
  const Checker checker{config.source};
  check_upper_bounds(config, checker);
  check_link_and_safety(config, checker);
  check_excitation_and_mmfm(config, checker);
  check_sweep_and_compare(config, checker);
}

}  // namespace rig::session
