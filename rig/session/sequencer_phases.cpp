// Pilot, excitation with online MMFM, swept sine and comparison (see session.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "rig/fra/h1.hpp"
#include "rig/fra/stepped_sine.hpp"
#include "rig/ident/identify.hpp"
#include "rig/ident/quality.hpp"
#include "rig/session/sequencer.hpp"
#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/excitation.hpp"

namespace rig::session {
namespace {

Eigen::VectorXd make_excitation(const TestConfig& c, Eigen::Index n, double sigma_pct,
                                std::uint64_t seed) {
  if (c.excitation.type == ExcitationType::kPrbs) {
    signal::PrbsOptions p;
    p.n = n;
    p.register_length = c.excitation.prbs_register_length;
    p.clock_divider = c.excitation.prbs_clock_divider;
    p.amplitude = sigma_pct;
    p.seed = seed;
    return signal::prbs_excitation(p);
  }
  signal::GaussianOptions g;
  g.n = n;
  g.dt_s = 1.0 / c.link.sample_rate_hz;
  g.bandwidth_hz = c.excitation.bandwidth_hz;
  g.sigma = sigma_pct;
  g.clip_sigma = kExcitationClipSigma;
  g.seed = seed;
  return signal::gaussian_excitation(g);
}

signal::CorrelatorKind correlator_kind(const std::string& name) {
  if (name == "fft") return signal::CorrelatorKind::kFft;
  if (name == "relay") return signal::CorrelatorKind::kRelay;
  if (name == "polarity") return signal::CorrelatorKind::kPolarity;
  return signal::CorrelatorKind::kDirect;
}

// Raised-cosine fade from 1 to 0 over n samples: the excitation ends without a step, which a
// lightly damped mode would answer with an overshoot of up to 1 + exp(-pi zeta / sqrt(1-zeta^2)).
double fade_out(long j, long n) {
  return j >= n ? 0.0
                : 0.5 * (1.0 + std::cos(M_PI * static_cast<double>(j) / static_cast<double>(n)));
}

// Samples the supervisor's soft start takes to reach full scale.
constexpr double kFadeOutS = 2.0;
// The supervisor's statistical cap holds the request's mean square for tens of seconds, so in
// a stepped sine it would mix the previous point's amplitude with this point's gain; the
// sweep's amplitudes are planned per frequency from the model instead (0 disables the cap;
// the envelope back-off and the trip stay in force).
constexpr double kSinePeakToRms = 0.0;
// Relative standard error aimed at per sweep point: 1 degree (0.0175 rad, 0.15 dB), so that
// three standard errors stay inside a +-3 deg / +-0.5 dB comparison.
constexpr double kSweepTargetRelStd = 0.0175;
constexpr double kSweepMaxIntegrateFactor = 4.0;

long soft_start_samples(const SupervisorConfig& s) {
  return static_cast<long>(std::ceil(1.0 / (s.backoff.recover_rate_per_s * s.dt_s))) + 1;
}

}  // namespace

double Sequencer::timing_correction_s() const {
  const double dt_s = loop_.dt_s();
  const double read_lag_s = data_.config.link.lockstep_ticks > 0 ? dt_s : 0.0;
  return read_lag_s - 0.5 * dt_s;
}

void Sequencer::correct_timing(std::vector<fra::FrfPoint>& frf) const {
  const double c = timing_correction_s();
  for (auto& p : frf) p.phase_deg = fra::wrap_deg(p.phase_deg - 360.0 * p.freq_hz * c);
}

bool Sequencer::pilot() {
  const TestConfig& c = data_.config;
  const double rate = c.link.sample_rate_hz;
  const long soft = soft_start_samples(supervisor_config());
  const long n = soft + std::lround(c.pilot.duration_s * rate);
  const Eigen::VectorXd e = make_excitation(c, n, c.pilot.amplitude_pct, c.excitation.seed + 7919);
  std::vector<double> u, y;
  long k_now = 0;
  const bool ok = supervised_phase(
      Phase::kPilot,
      [&](long k) -> std::optional<double> {
        k_now = k;
        loop_.status().eta_s = static_cast<double>(n - k) / rate;
        if (k >= n) return std::nullopt;
        return e(k);
      },
      [&](const TickResult& r) {
        if (k_now < soft) return;  // scale still rising
        u.push_back(r.out.excitation_pct);
        y.push_back(r.sample->power_kw - p0_kw_);
      });
  if (!ok) return false;
  PilotPlanLimits limits;
  limits.band_kw = c.safety.band_pct / 100.0 * p0_kw_;
  limits.plan_fraction = c.safety.plan_fraction;
  limits.clamp_pct = c.safety.clamp_pct;
  limits.noise_std_kw = data_.steady->noise_pct / 100.0 * p0_kw_;
  data_.pilot = off_loop([&] { return analyse_pilot(u, y, limits); });
  pilot_u_ = u;
  pilot_y_ = y;
  if (!data_.pilot->ok) {
    fail(kExitLinkFault, data_.pilot->reason);
    return false;
  }
  data_.excitation_sigma_pct = data_.pilot->planned_std_pct;
  view_.message(fmt::format(
      "pilot: gain {:.1f} kW/%, planned excitation std {:.3f} % (predicted peak {:.1f} of {:.1f} "
      "kW){}",
      data_.pilot->gain_kw_per_pct, data_.pilot->planned_std_pct, data_.pilot->predicted_peak_kw,
      limits.band_kw, data_.pilot->limited_by_clamp ? ", limited by the clamp" : ""));
  return true;
}

void Sequencer::show_estimate(const BlockEstimate& e) {
  auto& est = loop_.status().estimates;
  est.clear();
  if (!e.ok) {
    loop_.status().flags = {"estimate failed"};
    return;
  }
  loop_.status().flags.clear();
  if (e.derived.valid) {
    est.push_back({"K", e.derived.gain, e.derived.gain_std});
    est.push_back({"fn", e.derived.fn_hz, e.derived.fn_hz_std});
    est.push_back({"zeta", e.derived.zeta, e.derived.zeta_std});
  } else {
    for (const auto& p : e.parameters) est.push_back({p.name, p.value, p.std_error});
  }
  est.push_back({"Td", e.delay_s + timing_correction_s(),
                 e.parameters.empty() ? 0.0 : e.parameters.back().std_error});
  if (std::isfinite(e.max_rel_std_error)) {
    est.push_back({"rse", e.max_rel_std_error, 0.0});
  }
}

bool Sequencer::excite() {
  const TestConfig& c = data_.config;
  const double rate = c.link.sample_rate_hz;
  OnlineMmfmOptions o;
  o.order = {c.mmfm.order_n, c.mmfm.order_m};
  o.delay_s = c.mmfm.delay_s;
  o.correlator.lags = c.mmfm.lags;
  o.correlator.skip = c.mmfm.skip;
  o.correlator.kind = correlator_kind(c.mmfm.correlator);
  o.correlator.dt_s = 1.0 / rate;
  o.block_samples = c.mmfm.block_size;
  o.exponential = c.mmfm.averaging == "exponential";
  o.weight = c.mmfm.averaging_w;
  o.ac_coupling_rc_s = c.excitation.ac_coupling_rc_s;
  o.target_rel_std_error = c.mmfm.target_rel_std_error;
  // Realtime: a block estimate (tens of ms) must not delay the next exchange, so it runs on a
  // worker and the stopping rule sees it a few ticks later. Lockstep keeps it inside the tick
  // so that a seed gives the same recording.
  o.asynchronous = c.link.lockstep_ticks == 0;
  OnlineMmfm online(o);
  const long max_n = std::lround(c.mmfm.max_duration_s * rate);
  const long min_n = std::lround(c.mmfm.min_duration_s * rate);
  const long fade_n = std::lround(kFadeOutS * rate);
  const Eigen::VectorXd e =
      make_excitation(c, max_n + fade_n, data_.excitation_sigma_pct, c.excitation.seed);
  bool stop = false;
  long k_now = 0;
  long k_stop = max_n;
  data_.stop_reason = "maximum duration reached";
  const bool ok = supervised_phase(
      Phase::kExcite,
      [&](long k) -> std::optional<double> {
        k_now = k;
        if (stop) k_stop = std::min(k_stop, k);
        loop_.status().eta_s = static_cast<double>(std::min(max_n, k_stop) + fade_n - k) / rate;
        if (k >= k_stop + fade_n) return std::nullopt;
        return e(k) * (k < k_stop ? 1.0 : fade_out(k - k_stop, fade_n));
      },
      [&](const TickResult& r) {
        const double u = r.out.excitation_pct;
        const double y = r.sample->power_kw - p0_kw_;
        exc_u_.push_back(u);
        exc_y_.push_back(y);
        if (auto est = online.push(u, y)) {
          show_estimate(*est);
          if (!stop && online.converged() && k_now >= min_n) {
            stop = true;
            data_.stop_reason = fmt::format("every relative standard error below {:.3g}",
                                            c.mmfm.target_rel_std_error);
          }
        }
      });
  loop_.status().estimates.clear();
  off_loop([&] { analyse_excitation(online); });
  if (ok)
    view_.message(fmt::format(
        "excitation: {:.0f} s, applied std {:.3f} % of {:.3f} % "
        "planned, stopped: {}",
        data_.excitation_s, data_.applied_std_pct, data_.excitation_sigma_pct, data_.stop_reason));
  return ok && excitation_supports_model();
}

void Sequencer::analyse_excitation(OnlineMmfm& online) {
  const TestConfig& c = data_.config;
  const double rate = c.link.sample_rate_hz;
  online.finish();
  data_.excitation_s = static_cast<double>(exc_u_.size()) / rate;
  data_.history = online.history();
  for (auto& h : data_.history) h.delay_s += timing_correction_s();
  data_.ruu = online.ruu();
  data_.ryu = online.ryu();
  try {
    data_.mmfm = online.final_result();
    data_.mmfm->delay_s = std::max(0.0, data_.mmfm->delay_s + timing_correction_s());
    data_.mmfm->model.delay_s = data_.mmfm->delay_s;
    if (!data_.mmfm->parameters.empty() && data_.mmfm->parameters.back().name == "delay_s") {
      data_.mmfm->parameters.back().value = data_.mmfm->delay_s;
    }
    if (data_.mmfm->derived.valid && data_.mmfm->derived.fn_hz > 0.0) {
      resonance_hz_ = data_.mmfm->derived.fn_hz;
    }
  } catch (const std::exception& ex) {
    data_.mmfm_error = ex.what();
    loop_.event("warning", "MMFM estimate failed: " + data_.mmfm_error);
  }
  if (exc_u_.size() >= 512) {
    fra::WelchOptions w;
    w.segment_length = std::min<Eigen::Index>(1024, static_cast<Eigen::Index>(exc_u_.size()) / 4);
    w.f_min_hz = 0.05;
    w.f_max_hz = std::min(rate / 2.0, 2.0 * c.sweep.to_hz);
    data_.h1 = fra::h1_estimate(Eigen::Map<const Eigen::VectorXd>(exc_u_.data(), exc_u_.size()),
                                Eigen::Map<const Eigen::VectorXd>(exc_y_.data(), exc_y_.size()),
                                1.0 / rate, w);
    correct_timing(data_.h1);
  }
  const Eigen::Map<const Eigen::VectorXd> u(exc_u_.data(),
                                            static_cast<Eigen::Index>(exc_u_.size()));
  const Eigen::Map<const Eigen::VectorXd> y(exc_y_.data(),
                                            static_cast<Eigen::Index>(exc_y_.size()));
  if (u.size() > 1) {
    data_.applied_std_pct =
        std::sqrt((u.array() - u.mean()).square().sum() / static_cast<double>(u.size() - 1));
  }
  check_excitation_quality(u, y);
}

// The pre-estimation checks of rig/ident/quality on the excitation record, after the same
// matched AC coupling the online estimate used. Fatal findings mean no model.
void Sequencer::check_excitation_quality(const Eigen::VectorXd& u, const Eigen::VectorXd& y) {
  const TestConfig& c = data_.config;
  ident::QualityOptions q;
  q.correlator.lags = c.mmfm.lags;
  q.correlator.skip = c.mmfm.skip;
  q.order = {c.mmfm.order_n, c.mmfm.order_m};
  q.delay_estimated = !c.mmfm.delay_s.has_value();
  const double dt_s = 1.0 / c.link.sample_rate_hz;
  if (u.size() <= 4 * c.mmfm.lags) {
    data_.quality_flags.push_back("excitation record shorter than four correlation windows");
    return;
  }
  try {
    const double rc = c.excitation.ac_coupling_rc_s;
    const Eigen::VectorXd uc = rc > 0.0 ? signal::ac_couple(u, dt_s, rc) : Eigen::VectorXd(u);
    const Eigen::VectorXd yc = rc > 0.0 ? signal::ac_couple(y, dt_s, rc) : Eigen::VectorXd(y);
    const ident::QualityReport report = ident::check_quality(uc, yc, dt_s, q);
    for (const auto& f : report.flags) {
      if (f.severity == ident::Severity::kFatal)
        data_.quality_flags.push_back(f.name + ": " + f.message);
    }
  } catch (const std::exception& e) {
    data_.quality_flags.push_back(std::string("data-quality check failed: ") + e.what());
  }
}

bool Sequencer::excitation_supports_model() {
  const TestConfig& c = data_.config;
  const double planned = data_.excitation_sigma_pct;
  const double share = planned > 0.0 ? data_.applied_std_pct / planned : 0.0;
  std::string why;
  if (share < c.mmfm.min_applied_fraction) {
    why = fmt::format(
        "the applied excitation (std {:.4f} %) was {:.0f} % of the planned {:.4f} % "
        "(mmfm.min_applied_fraction = {:g}): the supervisor held it back",
        data_.applied_std_pct, 100.0 * share, planned, c.mmfm.min_applied_fraction);
  } else if (!data_.quality_flags.empty()) {
    why = "the excitation data fail a quality check: " + data_.quality_flags.front();
  } else if (!data_.mmfm) {
    why = "the MMFM estimate failed: " + data_.mmfm_error;
  } else if (!data_.mmfm->model.is_stable()) {
    why = "the MMFM model is unstable";
  }
  if (why.empty()) return true;
  data_.model_rejected = why;
  fail(kExitAcceptance, "no model: " + why);
  return false;
}

// Largest sine amplitude whose sudden stop (a trip, or the step from one point to the next,
// which starts at phase zero) stays below the supervisor's back-off threshold: a step of A
// gives a peak of A |K| (1 + overshoot) for a second-order mode, overshoot =
// exp(-pi zeta / sqrt(1 - zeta^2)); without a valid model, overshoot 1.
double Sequencer::step_safe_amplitude_pct(const ident::TransferFunction& prior,
                                          const ident::DerivedFigures& d) const {
  const double gain = std::abs(prior.dc_gain());
  double overshoot = 1.0;
  if (d.valid && d.zeta > 0.0 && d.zeta < 1.0) {
    overshoot = std::exp(-M_PI * d.zeta / std::sqrt(1.0 - d.zeta * d.zeta));
  }
  const double band_kw = data_.config.safety.band_pct / 100.0 * p0_kw_;
  if (!(gain > 0.0) || !std::isfinite(gain)) return data_.config.safety.clamp_pct;
  const double fraction =
      std::min(data_.config.safety.plan_fraction, 0.9 * supervisor_config().backoff.start_fraction);
  return fraction * band_kw / (gain * (1.0 + overshoot));
}

bool Sequencer::sweep() {
  const TestConfig& c = data_.config;
  if (!c.sweep.enabled) return true;
  const double rate = c.link.sample_rate_hz;
  const ident::TransferFunction prior = data_.mmfm ? data_.mmfm->model : prior_from_pilot();
  fra::SweepPlanOptions p;
  p.f_start_hz = c.sweep.from_hz;
  p.f_stop_hz = c.sweep.to_hz;
  p.points = c.sweep.points;
  p.dt_s = 1.0 / rate;
  const auto d = data_.mmfm ? data_.mmfm->derived : ident::DerivedFigures{};
  if (d.valid && d.zeta > 0.0 && d.fn_hz > 0.0) {
    p.slowest_time_constant_s = 1.0 / (d.zeta * 2.0 * M_PI * d.fn_hz);
  }
  p.settle_time_constants = c.sweep.settle_time_constants;
  p.min_settle_cycles = static_cast<int>(std::ceil(c.sweep.settle_cycles));
  p.min_integrate_cycles = static_cast<int>(std::ceil(c.sweep.integrate_cycles));
  p.min_integrate_s = c.sweep.min_integrate_s;
  // Points whose amplitude is capped far below the band (above the resonance) integrate
  // until the lock-in's relative standard error is kSweepTargetRelStd, at most
  // kSweepMaxIntegrateFactor times the minimum (stepped_sine_plan.hpp, noise rule).
  p.noise_rms_kw = data_.steady->noise_pct / 100.0 * p0_kw_;
  p.target_rel_std = kSweepTargetRelStd;
  p.max_integrate_s = kSweepMaxIntegrateFactor * c.sweep.min_integrate_s;
  p.amplitude.band_kw = c.safety.band_pct / 100.0 * p0_kw_;
  // Below the supervisor's back-off threshold (start_fraction of the band): a back-off inside
  // a point changes the amplitude mid-integration and biases that point.
  p.amplitude.plan_fraction =
      std::min(c.safety.plan_fraction, 0.9 * supervisor_config().backoff.start_fraction);
  p.amplitude.noise_peak_kw = 3.0 * data_.steady->noise_pct / 100.0 * p0_kw_;
  p.amplitude.max_amplitude_pct = std::min(c.safety.clamp_pct, step_safe_amplitude_pct(prior, d));
  fra::SweepPlan plan;
  std::string plan_error;
  off_loop([&] {
    try {
      plan = fra::make_sweep_plan(p, fra::as_response_fn(prior));
    } catch (const std::exception& ex) {
      plan_error = ex.what();
    }
  });
  if (!plan_error.empty()) {
    loop_.event("warning", "swept sine skipped: " + plan_error);
    return true;
  }
  fra::SteppedSineAnalyser analyser(plan);
  const long soft = soft_start_samples(supervisor_config());
  const long fade_n = std::lround(kFadeOutS * rate);
  long k_now = 0;
  long k_done = -1;
  const bool ok = supervised_phase(
      Phase::kSweep,
      [&](long k) -> std::optional<double> {
        k_now = k;
        if (k < soft) return 0.0;
        if (analyser.done()) {
          // Continue the last point's sine A sin(2 pi f n dt) while fading it out.
          if (k_done < 0) k_done = k;
          const auto& last = plan.points.back();
          const long j = k - k_done;
          if (j >= fade_n) return std::nullopt;
          const double n = static_cast<double>(last.total_samples() + j);
          return last.amplitude_pct * std::sin(2.0 * M_PI * last.freq_hz * n / rate) *
                 fade_out(j, fade_n);
        }
        const auto& pts = analyser.plan().points;
        loop_.status().phase = fmt::format("sweep {:.2f}Hz", pts[analyser.point_index()].freq_hz);
        return analyser.excitation_pct();
      },
      [&](const TickResult& r) {
        if (k_now < soft || analyser.done()) return;
        if (auto point = analyser.push(r.out.excitation_pct, r.sample->power_kw - p0_kw_)) {
          if (!point->good) loop_.status().flags = {"sweep point below quality"};
        }
        loop_.status().eta_s = plan.duration_s() - static_cast<double>(k_now - soft) / rate;
      },
      kSinePeakToRms);
  data_.sweep = analyser.frf();
  correct_timing(data_.sweep);
  return ok;
}

// Sweep without an excitation phase: a second-order MMFM fit of the pilot record plans the
// amplitudes; when that fails, a flat prior of five times the pilot's broadband gain (the
// resonance peak of a damping ratio 0.1 mode) keeps them conservative.
ident::TransferFunction Sequencer::prior_from_pilot() {
  const double dt_s = 1.0 / data_.config.link.sample_rate_hz;
  try {
    ident::IdentifyOptions o;
    o.order = ident::ModelOrder{2, 0};
    o.correlator.lags = data_.config.mmfm.lags;
    const auto r = ident::identify(
        Eigen::Map<const Eigen::VectorXd>(pilot_u_.data(), pilot_u_.size()),
        Eigen::Map<const Eigen::VectorXd>(pilot_y_.data(), pilot_y_.size()), dt_s, o);
    if (r.model.is_stable()) return r.model;
  } catch (const std::exception& ex) {
    loop_.event("warning", std::string("pilot model failed, flat prior used: ") + ex.what());
  }
  ident::TransferFunction flat;
  flat.num = Eigen::VectorXd::Constant(1, 5.0 * (data_.pilot ? data_.pilot->gain_kw_per_pct : 1.0));
  flat.den = Eigen::VectorXd::Constant(1, 1.0);
  return flat;
}

void Sequencer::compare() {
  const TestConfig& c = data_.config;
  if (!data_.mmfm) return;
  fra::CompareTolerances tol;
  tol.mag_db = c.compare.mag_tol_db;
  tol.phase_deg = c.compare.phase_tol_deg;
  tol.f_lo_hz = c.compare.from_hz;
  tol.f_hi_hz = c.compare.to_hz;
  tol.min_coherence = c.compare.min_coherence;
  if (!data_.sweep.empty()) data_.compare_sweep = fra::compare(data_.mmfm->model, data_.sweep, tol);
  if (!data_.h1.empty()) data_.compare_h1 = fra::compare(data_.mmfm->model, data_.h1, tol);
  if (data_.exit_code == kExitOk && c.sweep.enabled) {
    if (!data_.compare_sweep || data_.compare_sweep->verdict != fra::Verdict::kPass) {
      data_.exit_code = kExitAcceptance;
      data_.outcome = "acceptance check failed: " +
                      (data_.compare_sweep ? data_.compare_sweep->summary
                                           : std::string("no swept-sine response to compare"));
    }
  }
}

// Bounded: the governor's heartbeat rule has dropped the bias within 0.5 s anyway; these tries
// clear the enable and the held bias so that no later heartbeat writer re-applies them.
constexpr int kRampDownReconnects = 5;
constexpr auto kReconnectWait = std::chrono::milliseconds(400);

void Sequencer::finish() {
  RampDownResult& rd = data_.ramp_down;
  if (!activated_) {  // nothing was ever enabled
    link_.close();
    return;
  }
  rd.attempted = true;
  drivers::LinkResult<void> d = link_.deactivate();
  for (int attempt = 1; !d && attempt <= kRampDownReconnects; ++attempt) {
    loop_.event("link", fmt::format("ramp-down failed ({}); reconnecting, try {} of {}",
                                    d.error().message(), attempt, kRampDownReconnects));
    if (data_.config.link.lockstep_ticks == 0) std::this_thread::sleep_for(kReconnectWait);
    if (auto c = link_.configure(); !c) {
      d = c.error();
      continue;
    }
    ++rd.reconnects;
    d = link_.deactivate();
  }
  rd.cleared = d.has_value();
  if (!rd.cleared) {
    rd.error = d.error().message();
    loop_.event("link", "could not ramp down and clear the enable: " + rd.error +
                            " (the governor's heartbeat rule removes the bias)");
  } else if (rd.reconnects > 0) {
    loop_.event("link", fmt::format("reconnected ({}x), bias ramped to baseline and enable "
                                    "cleared",
                                    rd.reconnects));
  }
  link_.close();
}

}  // namespace rig::session
