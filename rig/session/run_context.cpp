#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/session/phase.hpp"

namespace rig::session {

int exit_code_for(TripCause cause) {
  switch (cause) {
    case TripCause::kNone:
      return kExitOk;
    case TripCause::kOutOfBand:
    case TripCause::kExternal:
    case TripCause::kRigFailure:
      return kExitSafety;
    default:
      return kExitLinkFault;  // stale, missing, NaN, link, governor status, echo
  }
}

RunContext::RunContext(SessionData& d, drivers::GovernorLink& l, io::RecordingWriter& recorder,
                       LiveView& v, const SessionOptions& options)
    : data(d),
      config(d.config),
      link(l),
      view(v),
      loop(l, d.config, recorder, v, options.abort, options.feed) {}

double RunContext::noise_kw() const {
  return data.steady ? data.steady->noise_pct / 100.0 * p0_kw : 0.0;
}

void RunContext::fail(int code, const std::string& outcome) {
  data.exit_code = code;
  data.outcome = outcome;
  loop.event(code == kExitSafety ? "trip" : "fault", outcome);
}

SupervisorConfig supervisor_config_from(const TestConfig& c) {
  const double rate_hz = c.link.sample_rate_hz;
  SupervisorConfig s;
  s.band_fraction = c.safety.band_pct / 100.0;
  s.band_override = c.safety.allow_band_above_3pct;
  s.baseline_bias_pct = 0.0;
  s.clamp_pct = c.safety.clamp_pct;
  s.ramp_rate_pct_per_s = c.safety.ramp_pct_per_s;
  s.dt_s = 1.0 / rate_hz;
  s.backoff.zero_fraction = std::max(c.safety.backoff_fraction, s.backoff.start_fraction + 0.05);
  s.backoff.plan_fraction = c.safety.plan_fraction;
  s.echo.tolerance_pct = c.safety.echo_tolerance_pct;
  s.echo.relative_tolerance = safety_defaults::kEchoRelativeTolerance;
  s.echo.delay_ticks = std::min(63, safety_defaults::ticks_at(c.safety.echo_delay_s, rate_hz));
  s.echo.max_bad_ticks = safety_defaults::ticks_at(c.safety.echo_max_bad_s, rate_hz);
  s.stale_ticks = safety_defaults::ticks_at(safety_defaults::kStaleTimeoutS, rate_hz);
  return s;
}

SupervisorConfig RunContext::supervisor_config(double peak_to_rms) const {
  SupervisorConfig s = supervisor_config_from(config);
  s.p0_kw = p0_kw;
  s.backoff.peak_to_rms = peak_to_rms;
  s.backoff.resonance_hz = std::min(resonance_hz, 0.9 * config.link.sample_rate_hz / 6.0);
  s.noise_rms_kw = noise_kw();
  s.plausible = plausible;
  if (acknowledged) {
    // Layer 0: from activation on the governor must keep the bias active and echo it.
    s.required_status_mask |= drivers::kBiasActive;
    s.echo.enabled = true;
  }
  return s;
}

bool RunContext::record_trip(const Supervisor& sup) {
  if (!sup.tripped()) return false;
  const TripRecord& trip = *sup.trip_record();
  data.trip = trip;
  fail(exit_code_for(trip.cause), fmt::format("{} in the {} phase: {}", to_string(trip.cause),
                                              to_string(loop.phase()), trip.text));
  return true;
}

double RunContext::timing_correction_s() const {
  const double read_lag_s = lockstep() ? dt_s() : 0.0;
  return read_lag_s - 0.5 * dt_s();
}

void RunContext::correct_timing(std::vector<model::FrfPoint>& frf) const {
  model::add_delay(frf, timing_correction_s());
}

double fade_out(long j, long n) {
  return j >= n ? 0.0
                : 0.5 * (1.0 + std::cos(M_PI * static_cast<double>(j) / static_cast<double>(n)));
}

long SupervisedPhase::soft_start_samples(const RunContext& ctx) {
  const SupervisorConfig s = ctx.supervisor_config();
  return static_cast<long>(std::ceil(1.0 / (s.backoff.recover_rate_per_s * s.dt_s))) + 1;
}

bool SupervisedPhase::run(RunContext& ctx) {
  if (!prepare(ctx)) return true;
  ctx.loop.set_phase(code());
  Supervisor sup(ctx.supervisor_config(peak_to_rms()));
  sup.start();
  long k = 0;
  bool exciting = true;
  while (!sup.done()) {
    double req = 0.0;
    if (exciting) {
      if (const std::optional<double> next = request(ctx, k)) {
        req = *next;
      } else {
        exciting = false;
        sup.finish();
      }
    }
    const TickResult r = ctx.loop.supervised(sup, req);
    // A reading that is not a number trips the supervisor at the next tick (not_finite); it
    // is no sample of the plant's answer, and one NaN in a phase's record poisons its
    // whole analysis (a power "not available" for good: the excitation's analysis of a record
    // ending in NaN took 3 minutes and up to 16 GB before it failed).
    const bool readable = r.sample && std::isfinite(r.sample->power_kw);
    if (readable && exciting && !sup.tripped()) {
      consume(ctx, r, k);
    } else {
      observe(ctx, r);
    }
    ++k;
    if (sup.tripped() && ctx.loop.link_gone()) break;  // nothing more can be written
  }
  ctx.loop.show(true);
  return conclude(ctx, !ctx.record_trip(sup));
}

}  // namespace rig::session
