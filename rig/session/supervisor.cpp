#include "rig/session/supervisor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace rig::session {

namespace {

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char line[200];
  std::snprintf(line, sizeof line, fmt, a, b, c);
  return line;
}

}  // namespace

// The governor's status in words: the bits that trip, then the raw word.
std::string Supervisor::status_text(std::uint16_t status) const {
  struct Bit {
    std::uint16_t mask;
    const char* when_set;
    const char* when_clear;
  };
  static constexpr Bit kBits[] = {
      {drivers::kRunning, "", "the set is not running (bit 0 clear)"},
      {drivers::kBreakerClosed, "", "the breaker is open (bit 1 clear)"},
      {drivers::kBiasActive, "", "the external bias is no longer active (bit 2 clear)"},
      {drivers::kHeartbeatLost, "the governor lost the heartbeat (bit 3)", ""},
      {drivers::kPlantFault, "the governor reports a plant fault (bit 4)", ""},
  };
  std::string words;
  for (const auto& b : kBits) {
    const bool set = (status & b.mask) != 0;
    const bool trips = set ? (config_.trip_status_mask & b.mask) != 0
                           : (config_.required_status_mask & b.mask) != 0;
    const char* text = set ? b.when_set : b.when_clear;
    if (trips && *text) words += (words.empty() ? "" : ", ") + std::string(text);
  }
  char raw[40];
  std::snprintf(raw, sizeof raw, " (status 0x%04x)", unsigned{status});
  return (words.empty() ? std::string("governor status") : words) + raw;
}

DeviationEnvelope::DeviationEnvelope(const BackoffConfig& config, double dt_s)
    : dt_s_(dt_s),
      decay_(std::exp(-dt_s / config.envelope_release_s)),
      w_r_(2.0 * std::numbers::pi * config.resonance_hz) {
  if (w_r_ > 0.0) {
    // 2nd-order Butterworth low-pass at 3 f_r, bilinear with prewarping, K = tan(pi fc dt).
    const double k = std::tan(std::numbers::pi * 3.0 * config.resonance_hz * dt_s);
    const double q = std::sqrt(2.0);
    const double norm = 1.0 / (1.0 + q * k + k * k);
    b0_ = k * k * norm;
    b1_ = 2.0 * b0_;
    b2_ = b0_;
    a1_ = 2.0 * (k * k - 1.0) * norm;
    a2_ = (1.0 - q * k + k * k) * norm;
  }
}

void DeviationEnvelope::reset() {
  primed_ = false;
  envelope_kw_ = 0.0;
}

double DeviationEnvelope::update(double d) {
  double free_swing = 0.0;
  if (w_r_ > 0.0) {
    if (!primed_) {  // start at rest on the first sample: no step into the derivative
      x1_ = x2_ = y1_ = y2_ = d;
      primed_ = true;
    }
    const double y0 = b0_ * d + b1_ * x1_ + b2_ * x2_ - a1_ * y1_ - a2_ * y2_;
    const double rate = (y0 - y1_) / dt_s_;
    x2_ = x1_;
    x1_ = d;
    y2_ = y1_;
    y1_ = y0;
    free_swing = std::hypot(y0, rate / w_r_);
  }
  envelope_kw_ = std::max({std::abs(d), free_swing, envelope_kw_ * decay_});
  return envelope_kw_;
}

Supervisor::Supervisor(const SupervisorConfig& config)
    : config_((validate(config), config)), envelope_(config.backoff, config.dt_s) {
  last_bias_pct_ = config_.baseline_bias_pct;
}

void Supervisor::start() {
  if (state_ != SupervisorState::kIdle) return;
  state_ = SupervisorState::kRunning;
  envelope_.reset();
  scale_ = 0.0;
  mean_d_ = 0.0;
  ms_d_ = config_.noise_rms_kw * config_.noise_rms_kw;  // no excitation yet: noise only
  ms_u_ = 0.0;
  ms_r_ = 0.0;
  ms_r_held_ = 0.0;
  g2_held_ = 0.0;
  last_bias_pct_ = config_.baseline_bias_pct;
  commands_[0] = config_.baseline_bias_pct;  // what the governor held before the phase
  head_ = 0;
  filled_ = 1;
  bad_echo_ticks_ = 0;
}

void Supervisor::finish() {
  if (state_ == SupervisorState::kRunning || state_ == SupervisorState::kBackingOff) {
    state_ = SupervisorState::kRampingDown;
  }
}

void Supervisor::trip(TripCause cause, std::string text) {
  if (trip_ || state_ == SupervisorState::kIdle || state_ == SupervisorState::kDone) return;
  // Taking effect in the next tick, which therefore counts as the trip tick.
  trip_ = TripRecord{cause, std::move(text), tick_ + 1};
  state_ = SupervisorState::kTripped;
}

bool Supervisor::active() const {
  return state_ == SupervisorState::kRunning || state_ == SupervisorState::kBackingOff ||
         state_ == SupervisorState::kRampingDown;
}

void Supervisor::judge(const drivers::Sample& s) {
  const double dev = s.power_kw - config_.p0_kw;
  if (!std::isfinite(s.power_kw)) {
    trip(TripCause::kNotFinite, "power reading is not finite");
  } else if ((s.status & config_.trip_status_mask) != 0 ||
             (s.status & config_.required_status_mask) != config_.required_status_mask) {
    trip(TripCause::kGovernorStatus, status_text(s.status));
  } else if (counter_backwards_) {
    trip(TripCause::kImplausible, format("sample counter went backwards to %.0f", s.counter));
  } else if (config_.plausible.speed && !(s.speed_rpm > 0.0)) {
    trip(TripCause::kImplausible,
         format("engine speed reads %.1f rpm on a running set", s.speed_rpm));
  } else if (config_.plausible.freq && !(s.freq_hz > 0.0)) {
    trip(TripCause::kImplausible,
         format("bus frequency reads %.3f Hz on a running set", s.freq_hz));
  } else if (unchanged_ticks_ >= config_.stale_ticks) {
    trip(TripCause::kStaleSample, format("sample counter %.0f unchanged for %.0f ticks", s.counter,
                                         static_cast<double>(unchanged_ticks_)));
  } else if (std::abs(dev) > config_.band_kw()) {
    trip(TripCause::kOutOfBand, format("power %.1f kW is %+.1f kW from P0 (band %.1f kW)",
                                       s.power_kw, dev, config_.band_kw()));
  }
  if (!trip_) judge_echo(s);
  if (trip_) trip_->tick = tick_;
}

// Layer 0: the echo matches one of the commands the governor may be showing (the newest
// delay_ticks + 1, newest first).
void Supervisor::judge_echo(const drivers::Sample& s) {
  const EchoCheck& e = config_.echo;
  if (!e.enabled || filled_ == 0) return;
  const int window = std::min(e.delay_ticks + 1, filled_);
  double nearest_cmd = commands_[head_];
  double nearest_err = std::numeric_limits<double>::infinity();
  for (int j = 0; j < window; ++j) {
    const double cmd = commands_[(head_ - j + kCommandHistory) % kCommandHistory];
    const double err = std::abs(s.bias_echo_pct - cmd);
    if (err <= e.tolerance_pct + e.relative_tolerance * std::abs(cmd)) {
      bad_echo_ticks_ = 0;
      return;
    }
    if (err < nearest_err) nearest_err = err, nearest_cmd = cmd;
  }
  if (++bad_echo_ticks_ > e.max_bad_ticks) {
    char line[200];
    std::snprintf(line, sizeof line,
                  "the governor's bias echo %.3f %% does not follow the command %.3f %% "
                  "(tolerance %.3f %% + %.0f %%) for %d ticks: the bias is not applied as sent",
                  s.bias_echo_pct, nearest_cmd, e.tolerance_pct, 100.0 * e.relative_tolerance,
                  bad_echo_ticks_);
    trip(TripCause::kBiasNotApplied, line);
  }
}

// A counter that moved backwards (by more than half its range, modulo 2^16).
void Supervisor::judge_counter(const drivers::Sample& s) {
  if (last_counter_) {
    const auto moved = static_cast<std::uint16_t>(s.counter - *last_counter_);
    counter_backwards_ = moved > 0x8000u;
  }
}

SupervisorOutput Supervisor::tick(const drivers::Sample& sample, double request_pct) {
  ++tick_;
  judge_counter(sample);
  // Stale-counter rule: consecutive ticks that returned the same counter.
  if (last_counter_ && *last_counter_ == sample.counter) {
    ++unchanged_ticks_;
  } else {
    unchanged_ticks_ = 0;
  }
  last_counter_ = sample.counter;
  const double dev = sample.power_kw - config_.p0_kw;
  if (active() && !trip_) {
    judge(sample);
    if (!trip_) {
      envelope_.update(dev);
      update_statistics(dev);
    }
  }
  return command(request_pct, dev);
}

SupervisorOutput Supervisor::tick(const drivers::LinkResult<drivers::Sample>& read,
                                  double request_pct) {
  if (read) return tick(read.value(), request_pct);
  TripCause cause = TripCause::kLinkError;
  if (read.error().kind == drivers::LinkErrorKind::kTimeout) cause = TripCause::kMissingSample;
  if (read.error().kind == drivers::LinkErrorKind::kStale) cause = TripCause::kStaleSample;
  ++tick_;
  if (active() && !trip_) {
    trip(cause, read.error().message());
    trip_->tick = tick_;
  }
  return command(request_pct, std::numeric_limits<double>::quiet_NaN());
}

SupervisorOutput Supervisor::tick_missing(double request_pct) {
  ++tick_;
  if (active() && !trip_) {
    trip(TripCause::kMissingSample, "no sample this tick");
    trip_->tick = tick_;
  }
  return command(request_pct, std::numeric_limits<double>::quiet_NaN());
}

void Supervisor::update_statistics(double d) {
  const BackoffConfig& b = config_.backoff;
  const double a = config_.dt_s / b.rms_time_constant_s;
  const double u = last_bias_pct_ - config_.baseline_bias_pct;  // applied last tick
  mean_d_ += a * (d - mean_d_);
  ms_d_ += a * (d * d - ms_d_);
  ms_u_ += a * (u * u - ms_u_);
  const double noise_var = config_.noise_rms_kw * config_.noise_rms_kw;
  const double var_d = ms_d_ - mean_d_ * mean_d_;
  g2_held_ *= std::exp(-config_.dt_s / b.statistics_hold_s);
  const bool fair_share = ms_u_ >= b.min_gain_share * ms_r_;
  if (ms_u_ > 1e-12 && fair_share && var_d > 2.0 * noise_var) {
    g2_held_ = std::max(g2_held_, (var_d - noise_var) / ms_u_);
  }
}

double Supervisor::statistical_cap() const {
  const BackoffConfig& b = config_.backoff;
  if (b.peak_to_rms <= 0.0) return 1.0;
  const double noise_var = config_.noise_rms_kw * config_.noise_rms_kw;
  const double limit = b.plan_fraction * config_.band_kw() / b.peak_to_rms;
  const double allowed = limit * limit - noise_var;
  if (allowed <= 0.0) return 0.0;  // the noise alone fills the planned band
  const double predicted = g2_held_ * ms_r_held_;
  return predicted > 0.0 ? std::min(1.0, std::sqrt(allowed / predicted)) : 1.0;
}

double Supervisor::ramp_toward_baseline() const {
  const double step = config_.ramp_rate_pct_per_s * config_.dt_s;
  const double diff = config_.baseline_bias_pct - last_bias_pct_;
  // The relative slack absorbs rounding in the accumulated steps, so the last step lands
  // exactly on the baseline instead of leaving a 1e-16 remainder for one more tick.
  if (std::abs(diff) <= step * (1.0 + 1e-9)) return config_.baseline_bias_pct;
  return last_bias_pct_ + std::copysign(step, diff);
}

SupervisorOutput Supervisor::command(double request_pct, double deviation_kw) {
  const double base = config_.baseline_bias_pct;
  double bias = base;
  switch (state_) {
    case SupervisorState::kIdle:
    case SupervisorState::kDone:
      scale_ = 0.0;
      break;
    case SupervisorState::kTripped:
    case SupervisorState::kRampingDown: {
      scale_ = 0.0;
      bias = ramp_toward_baseline();
      const bool trip_tick = trip_ && trip_->tick == tick_;
      if (bias == base && !trip_tick) state_ = SupervisorState::kDone;
      break;
    }
    case SupervisorState::kRunning:
    case SupervisorState::kBackingOff: {
      const BackoffConfig& b = config_.backoff;
      const double level = envelope_.value() / config_.band_kw();
      const double target =
          std::clamp((b.zero_fraction - level) / (b.zero_fraction - b.start_fraction), 0.0, 1.0);
      // A NaN request is no request; an infinite one is bounded before scaling (0 * inf).
      const double r = std::isnan(request_pct) ? 0.0 : std::clamp(request_pct, -1e6, 1e6);
      ms_r_ += config_.dt_s / b.rms_time_constant_s * (r * r - ms_r_);
      ms_r_held_ = std::max(ms_r_, ms_r_held_ * std::exp(-config_.dt_s / b.statistics_hold_s));
      const double cap = std::min(target, statistical_cap());
      scale_ = std::clamp(cap, scale_ - b.fall_rate_per_s * config_.dt_s,
                          scale_ + b.recover_rate_per_s * config_.dt_s);
      state_ = cap < 1.0 ? SupervisorState::kBackingOff : SupervisorState::kRunning;
      bias = base + scale_ * r;
      break;
    }
  }
  // Layer 4, last and unconditional.
  if (!std::isfinite(bias)) bias = base;
  bias = std::clamp(bias, -config_.clamp_pct, config_.clamp_pct);
  last_bias_pct_ = bias;
  head_ = (head_ + 1) % kCommandHistory;
  commands_[head_] = bias;
  filled_ = std::min(filled_ + 1, kCommandHistory);

  SupervisorOutput out;
  out.bias_pct = bias;
  out.excitation_pct = bias - base;
  out.scale = scale_;
  out.state = state_;
  out.trip_cause = trip_ ? trip_->cause : TripCause::kNone;
  out.heartbeat = ++heartbeat_;
  out.deviation_kw = deviation_kw;
  out.envelope_kw = envelope_.value();
  return out;
}

}  // namespace rig::session
