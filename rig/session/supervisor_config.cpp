// The supervisor's names and its configuration rules (supervisor.hpp).
#include <cmath>
#include <string>

#include "rig/session/supervisor.hpp"

namespace rig::session {

const char* to_string(SupervisorState state) {
  switch (state) {
    case SupervisorState::kIdle:
      return "idle";
    case SupervisorState::kRunning:
      return "running";
    case SupervisorState::kBackingOff:
      return "backing_off";
    case SupervisorState::kTripped:
      return "tripped";
    case SupervisorState::kRampingDown:
      return "ramping_down";
    case SupervisorState::kDone:
      return "done";
  }
  return "unknown";
}

const char* to_string(TripCause cause) {
  switch (cause) {
    case TripCause::kNone:
      return "none";
    case TripCause::kOutOfBand:
      return "out_of_band";
    case TripCause::kStaleSample:
      return "stale_sample";
    case TripCause::kMissingSample:
      return "missing_sample";
    case TripCause::kNotFinite:
      return "not_finite";
    case TripCause::kLinkError:
      return "link_error";
    case TripCause::kGovernorStatus:
      return "governor_status";
    case TripCause::kExternal:
      return "external";
    case TripCause::kBiasNotApplied:
      return "bias_not_applied";
    case TripCause::kImplausible:
      return "implausible_reading";
    case TripCause::kRigFailure:
      return "rig_failure";
  }
  return "unknown";
}

namespace {

constexpr double kMaxBandWithoutOverride = kStandardBandPct / 100.0;

void require(bool ok, const char* what) {
  if (!ok) throw SupervisorConfigError(std::string("supervisor config: ") + what);
}

}  // namespace

void validate(const SupervisorConfig& c) {
  require(std::isfinite(c.p0_kw) && c.p0_kw > 0.0, "p0_kw must be a finite power > 0");
  require(c.band_fraction > 0.0 && c.band_fraction < 1.0, "band_fraction must be in (0, 1)");
  require(c.band_fraction <= kMaxBandWithoutOverride || c.band_override,
          "band_fraction above 0.03 (3 % of P0) needs band_override");
  require(std::isfinite(c.clamp_pct) && c.clamp_pct > 0.0, "clamp_pct must be finite and > 0");
  require(std::isfinite(c.baseline_bias_pct) && std::abs(c.baseline_bias_pct) <= c.clamp_pct,
          "baseline_bias_pct must lie within +-clamp_pct");
  require(std::isfinite(c.ramp_rate_pct_per_s) && c.ramp_rate_pct_per_s > 0.0,
          "ramp_rate_pct_per_s must be finite and > 0");
  require(std::isfinite(c.dt_s) && c.dt_s > 0.0, "dt_s must be finite and > 0");
  require(c.stale_ticks >= 1, "stale_ticks must be >= 1");
  const BackoffConfig& b = c.backoff;
  require(b.start_fraction > 0.0 && b.start_fraction < b.zero_fraction && b.zero_fraction <= 1.0,
          "backoff fractions must satisfy 0 < start_fraction < zero_fraction <= 1");
  require(b.envelope_release_s > 0.0, "backoff.envelope_release_s must be > 0");
  require(b.recover_rate_per_s > 0.0, "backoff.recover_rate_per_s must be > 0");
  require(b.fall_rate_per_s > 0.0, "backoff.fall_rate_per_s must be > 0");
  require(b.min_gain_share >= 0.0 && b.min_gain_share <= 1.0,
          "backoff.min_gain_share must be in [0, 1]");
  const EchoCheck& e = c.echo;
  require(e.tolerance_pct >= 0.0 && e.relative_tolerance >= 0.0, "echo tolerances must be >= 0");
  require(e.delay_ticks >= 0 && e.delay_ticks < 64, "echo.delay_ticks must be 0 to 63");
  require(e.max_bad_ticks >= 0, "echo.max_bad_ticks must be >= 0");
  require(std::isfinite(c.noise_rms_kw) && c.noise_rms_kw >= 0.0,
          "noise_rms_kw must be finite and >= 0");
  require(b.plan_fraction > 0.0 && b.plan_fraction <= 1.0,
          "backoff.plan_fraction must be in (0, 1]");
  require(b.peak_to_rms >= 0.0, "backoff.peak_to_rms must be >= 0 (0 disables the cap)");
  require(b.rms_time_constant_s > 0.0, "backoff.rms_time_constant_s must be > 0");
  require(b.statistics_hold_s > 0.0, "backoff.statistics_hold_s must be > 0");
  require(b.resonance_hz >= 0.0 && 3.0 * b.resonance_hz < 0.5 / c.dt_s,
          "backoff.resonance_hz must be >= 0 and 3 resonance_hz below the Nyquist rate");
}

}  // namespace rig::session
