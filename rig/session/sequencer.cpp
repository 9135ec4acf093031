#include "rig/session/sequencer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/fra/h1.hpp"

namespace rig::session {

int exit_code_for(TripCause cause) {
  switch (cause) {
    case TripCause::kNone: return kExitPass;
    case TripCause::kOutOfBand:
    case TripCause::kExternal: return kExitSafety;
    default: return kExitFault;  // stale, missing, NaN, link error, governor status
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
  return s;
}

bool Sequencer::steady_state() {
  const TestConfig& c = data_.config;
  loop_.set_phase(Phase::kSteady);
  std::vector<double> t, p;
  const auto n = static_cast<long>(std::ceil(c.steady_state.duration_s * c.link.sample_rate_hz));
  for (long k = 0; k < n; ++k) {
    if (loop_.abort_requested()) {
      fail(kExitSafety, "operator abort during the steady-state check (nothing was written)");
      return false;
    }
    const TickResult r = loop_.observe();
    if (!r.sample) {
      auto again = link_.read();
      fail(kExitFault, "link fault during the steady-state check: " +
                           (again ? std::string("read failed") : again.error().message()));
      return false;
    }
    t.push_back(r.t_s);
    p.push_back(r.sample->power_kw);
    if (k == 0 && (r.sample->status & drivers::kRunning) == 0) {
      fail(kExitFault, "the governor reports the set is not running (status bit 0 clear)");
      return false;
    }
  }
  const SteadyStateResult s = check_steady_state(
      t, p, {c.steady_state.max_noise_pct, c.steady_state.max_drift_pct, c.steady_state.min_power_kw});
  data_.steady = s;
  if (!s.ok) {
    fail(kExitFault, "steady-state check failed, test not started: " + s.reason);
    return false;
  }
  p0_kw_ = s.p0_kw;
  loop_.set_p0(p0_kw_);
  view_.message(fmt::format("steady state: P0 {:.1f} kW, noise {:.3f} %, drift {:.3f} % over {:.0f} s",
                            s.p0_kw, s.noise_pct, s.drift_pct, s.duration_s));
  return true;
}

bool Sequencer::activate() {
  if (auto a = link_.activate(); !a) {
    fail(kExitFault, "cannot enable the external bias: " + a.error().message());
    return false;
  }
  // Baseline writes until the governor sees the heartbeat again (at most one second).
  const auto n = static_cast<long>(data_.config.link.sample_rate_hz);
  for (long k = 0; k < n; ++k) {
    const TickResult r = loop_.prime();
    if (r.sample && (r.sample->status & drivers::kHeartbeatLost) == 0 && k >= 2) return true;
  }
  fail(kExitFault, "the governor still reports the heartbeat lost one second after activation");
  return false;
}

bool Sequencer::tripped(const Supervisor& sup) {
  if (!sup.tripped()) return false;
  const TripRecord& trip = *sup.trip_record();
  data_.trip = trip;
  fail(exit_code_for(trip.cause),
       fmt::format("{} in the {} phase: {}", to_string(trip.cause), to_string(loop_.phase()),
                   trip.text));
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
