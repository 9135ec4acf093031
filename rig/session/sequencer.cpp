#include "rig/session/sequencer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/fra/h1.hpp"

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

Sequencer::Sequencer(SessionData& data, drivers::GovernorLink& link, io::RecordingWriter& recorder,
                     LiveView& view, const SessionOptions& options)
    : data_(data),
      link_(link),
      view_(view),
      loop_(link, data.config, recorder, view, options.abort) {}

void Sequencer::fail(int code, const std::string& outcome) {
  data_.exit_code = code;
  data_.outcome = outcome;
  loop_.event(code == kExitSafety ? "trip" : "fault", outcome);
}

SupervisorConfig Sequencer::supervisor_config(double peak_to_rms) const {
  const TestConfig& c = data_.config;
  SupervisorConfig s;
  s.p0_kw = p0_kw_;
  s.band_fraction = c.safety.band_pct / 100.0;
  s.band_override = c.safety.allow_band_above_3pct;
  s.baseline_bias_pct = 0.0;
  s.clamp_pct = c.safety.clamp_pct;
  s.ramp_rate_pct_per_s = c.safety.ramp_pct_per_s;
  s.dt_s = loop_.dt_s();
  s.backoff.zero_fraction = std::max(c.safety.backoff_fraction, s.backoff.start_fraction + 0.05);
  s.backoff.plan_fraction = c.safety.plan_fraction;
  s.backoff.peak_to_rms = peak_to_rms;
  s.backoff.resonance_hz = std::min(resonance_hz_, 0.9 * c.link.sample_rate_hz / 6.0);
  if (data_.steady) s.noise_rms_kw = data_.steady->noise_pct / 100.0 * p0_kw_;
  s.plausible = plausible_;
  if (bias_acknowledged_) {
    // Layer 0: from activation on the governor must keep the bias active and echo it.
    s.required_status_mask |= drivers::kBiasActive;
    s.echo.enabled = true;
    s.echo.tolerance_pct = c.safety.echo_tolerance_pct;
    s.echo.delay_ticks = std::min(
        63, static_cast<int>(std::ceil(c.safety.echo_delay_s * c.link.sample_rate_hz - 1e-9)));
    s.echo.max_bad_ticks =
        static_cast<int>(std::ceil(c.safety.echo_max_bad_s * c.link.sample_rate_hz - 1e-9));
  }
  return s;
}

bool Sequencer::steady_state() {
  const TestConfig& c = data_.config;
  loop_.set_phase(Phase::kSteady);
  std::vector<double> t, p;
  const auto n = static_cast<long>(std::ceil(c.steady_state.duration_s * c.link.sample_rate_hz));
  bool saw_speed = true, saw_freq = true;
  for (long k = 0; k < n; ++k) {
    if (loop_.abort_requested()) {
      fail(kExitSafety, "operator abort during the steady-state check (nothing was written)");
      return false;
    }
    const TickResult r = loop_.observe();
    if (!loop_.rig_failure().empty()) {
      fail(kExitSafety, loop_.rig_failure() + " (steady-state check, nothing was written)");
      return false;
    }
    if (!r.sample) {
      fail(kExitLinkFault, "link fault during the steady-state check: " + loop_.last_link_error());
      return false;
    }
    saw_speed = saw_speed && r.sample->speed_rpm > 0.0;
    saw_freq = saw_freq && r.sample->freq_hz > 0.0;
    t.push_back(r.t_s);
    p.push_back(r.sample->power_kw);
    if (k == 0 && (r.sample->status & drivers::kRunning) == 0) {
      fail(kExitLinkFault, "the governor reports the set is not running (status bit 0 clear)");
      return false;
    }
  }
  const SteadyStateResult s = check_steady_state(
      t, p,
      {c.steady_state.max_noise_pct, c.steady_state.max_drift_pct, c.steady_state.min_power_kw});
  data_.steady = s;
  if (!s.ok) {
    fail(kExitLinkFault, "steady-state check failed, test not started: " + s.reason);
    return false;
  }
  p0_kw_ = s.p0_kw;
  loop_.set_p0(p0_kw_);
  // A reading the governor gave all through the steady state must not drop to 0 later.
  plausible_.speed = saw_speed;
  plausible_.freq = saw_freq;
  view_.message(
      fmt::format("steady state: P0 {:.1f} kW, noise {:.3f} %, drift {:.3f} % over {:.0f} s",
                  s.p0_kw, s.noise_pct, s.drift_pct, s.duration_s));
  return true;
}

// Enables the external bias, then writes the baseline until the governor reports the bias
// active (status bit 2) with a live heartbeat, at most safety.activation_timeout_s (layer 0).
bool Sequencer::activate() {
  const TestConfig& c = data_.config;
  activated_ = true;  // from here on finish() clears the enable, whatever happens
  if (auto a = link_.activate(); !a) {
    fail(kExitLinkFault, "cannot enable the external bias: " + a.error().message());
    return false;
  }
  const auto n =
      static_cast<long>(std::ceil(c.safety.activation_timeout_s * c.link.sample_rate_hz));
  std::uint16_t status = 0;
  bool read_any = false;
  for (long k = 0; k < n; ++k) {
    const TickResult r = loop_.prime();
    if (!r.sample) continue;
    read_any = true;
    status = r.sample->status;
    const bool active = (status & drivers::kBiasActive) != 0;
    const bool heartbeat = (status & drivers::kHeartbeatLost) == 0;
    if (active && heartbeat && k >= 2) {
      bias_acknowledged_ = true;
      return true;
    }
  }
  if (!read_any) {
    fail(kExitLinkFault, "link fault after enabling the external bias: " + loop_.last_link_error());
  } else if ((status & drivers::kBiasActive) == 0) {
    fail(kExitLinkFault,
         fmt::format("the governor did not report the external bias active (status bit 2) within "
                     "{:g} s of enabling it (status 0x{:04x}): it does not accept the bias",
                     c.safety.activation_timeout_s, status));
  } else {
    fail(kExitLinkFault, fmt::format("the governor still reports the heartbeat lost {:g} s after "
                                     "activation (status 0x{:04x})",
                                     c.safety.activation_timeout_s, status));
  }
  return false;
}

bool Sequencer::tripped(const Supervisor& sup) {
  if (!sup.tripped()) return false;
  const TripRecord& trip = *sup.trip_record();
  data_.trip = trip;
  fail(exit_code_for(trip.cause), fmt::format("{} in the {} phase: {}", to_string(trip.cause),
                                              to_string(loop_.phase()), trip.text));
  return true;
}

bool Sequencer::supervised_phase(Phase phase, const Request& request, const Consume& consume,
                                 double peak_to_rms) {
  loop_.set_phase(phase);
  Supervisor sup(supervisor_config(peak_to_rms));
  sup.start();
  long k = 0;
  bool exciting = true;
  while (!sup.done()) {
    double req = 0.0;
    if (exciting) {
      const std::optional<double> next = request(k);
      if (next) {
        req = *next;
      } else {
        exciting = false;
        sup.finish();
      }
    }
    const TickResult r = loop_.supervised(sup, req);
    if (r.sample && exciting && !sup.tripped()) consume(r);
    ++k;
    if (sup.tripped() && loop_.link_gone()) break;  // nothing more can be written
  }
  loop_.show(true);
  return !tripped(sup);
}

}  // namespace rig::session
