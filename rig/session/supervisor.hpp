// Power supervisor (DESIGN.md section 8): the only path from an excitation value to the bias
// written to the governor. Pure and deterministic: one call per tick, no clock, no I/O.
//
//   Supervisor sup(config);            // throws SupervisorConfigError on a bad config
//   sup.start();
//   while (!sup.done()) {
//     auto out = sup.tick(latest_read, excitation.next());   // LinkResult<Sample> or Sample
//     link.write(out.bias_pct);        // out.heartbeat is advanced every tick
//     if (write failed) sup.trip(TripCause::kLinkError, err.message());
//     if (excitation finished) sup.finish();
//   }
//
// Layers applied every tick, in order:
//  (3) trip: a sample with |P - P0| > band, a stale counter (unchanged for stale_ticks
//      consecutive ticks), a missing sample, a link error, non-finite power or a governor
//      status fault trips in the same tick: the request is ignored from that tick on (scale
//      0) and the bias moves from its last value to the baseline at ramp_rate_pct_per_s.
//      The first cause is latched with a one-line text.
//  (2) back-off: the envelope of d = P - P0 predicts how far the plant will swing even if
//      the excitation stopped now. A lightly damped mode at w_r = 2 pi resonance_hz holding
//      d_f and d_f' (d low-passed at 3 resonance_hz by a 2nd-order Butterworth, so that
//      noise and 50 Hz pick-up do not reach the derivative) swings freely with amplitude
//          A = sqrt(d_f^2 + (d_f' / w_r)^2),
//      which rises as soon as energy enters the mode, a quarter cycle before |d| peaks. With
//      a peak hold that releases with envelope_release_s,
//          env_k = max(|d_k|, A_k, env_{k-1} exp(-dt / envelope_release_s)),
//      the target scale is  s* = clamp((zero_fraction - env/band) /
//                                      (zero_fraction - start_fraction), 0, 1);
//      A second, statistical cap corrects an amplitude plan built on a wrong gain: with
//      exponentially weighted (rms_time_constant_s) variance of d, mean squares of the
//      applied excitation u and of the request r, and the noise variance s_n^2 of the
//      steady-state check, the observed gain is g^2 = (var d - s_n^2)^+ / ms(u) and the
//      predicted peak at scale s is peak_to_rms sqrt(s^2 g^2 ms(r) + s_n^2); keeping it
//      within plan_fraction of the band gives
//          s_cap = sqrt((plan_fraction band / peak_to_rms)^2 - s_n^2) / (g sqrt(ms(r))).
//      g^2 and ms(r) are held at their recent maxima (released with statistics_hold_s), so
//      that a lull in a random excitation, or a stretch of it away from the resonance, does
//      not open the cap just before the next burst. g^2 enters the hold only once the
//      response stands out of the noise (var d > 2 s_n^2): set noise_rms_kw, or the cap
//      learns noise / tiny excitation at the soft start and stays needlessly low.
//      g^2 is learnt only while the applied excitation is a fair share of the request
//      (ms(u) >= min_gain_share ms(r)): at a soft start, or while the cap holds the scale
//      low, var d over a tiny ms(u) is noise divided by almost nothing, and learning it
//      latched the cap near zero for the whole phase (an excitation that collapsed).
//      The applied scale falls towards min(s*, s_cap) at most fall_rate_per_s (no bias step)
//      and rises at most recover_rate_per_s (which is also the soft start from 0).
//  (0) bias acknowledgement, when echo.enabled: the governor's echo of the applied bias
//      (Sample::bias_echo_pct) must match one of the last echo.delay_ticks + 1 commands
//      within echo.tolerance_pct + echo.relative_tolerance |command|; more than
//      echo.max_bad_ticks consecutive mismatches trip (kBiasNotApplied).
//  (4) clamp, always last: |bias| <= clamp_pct whatever the request or estimate (a NaN
//      request counts as 0).
//  (5) heartbeat: incremented every tick; the link writes it with the bias.
// Layer (1), the amplitude plan, is rig/session/amplitude_plan.hpp.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "drivers/governor_link.hpp"
#include "rig/session/safety_defaults.hpp"

namespace rig::session {

enum class SupervisorState { kIdle, kRunning, kBackingOff, kTripped, kRampingDown, kDone };
enum class TripCause {
  kNone,
  kOutOfBand,       // |P - P0| above the band
  kStaleSample,     // sample counter not advancing
  kMissingSample,   // no sample this tick (timeout)
  kNotFinite,       // NaN/Inf power
  kLinkError,       // link read/write failure
  kGovernorStatus,  // status: heartbeat lost, plant fault, not running, bias not active
  kExternal,        // tripped by the caller (operator abort, a phase's fault)
  kBiasNotApplied,  // the governor's echo does not follow the command (layer 0)
  kImplausible,     // a reading that cannot be true: speed or frequency 0, counter backwards
  kRigFailure,      // the rig itself failed (recording or report write, disk full)
};
const char* to_string(SupervisorState state);
const char* to_string(TripCause cause);

struct SupervisorConfigError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct BackoffConfig {
  double start_fraction = 0.6;  // envelope / band where the scale starts to fall
  double zero_fraction = safety_defaults::kBackoffFraction;  // envelope / band: scale 0
  double envelope_release_s = 2.0;                           // peak-hold decay time constant
  double recover_rate_per_s = 0.1;  // fastest rise of the scale (soft start: 10 s to 1)
  double fall_rate_per_s = 5.0;     // fastest fall of the scale (1 to 0 in 0.2 s, no step)
  double min_gain_share = 0.05;     // learn g^2 only while ms(u) >= this ms(r)
  double resonance_hz = 2.0;        // dominant mode (prior or pilot); 0: no derivative term
  double plan_fraction = safety_defaults::kPlanFraction;  // cap: predicted peak, band share
  double peak_to_rms = 4.0;          // response peak / rms: 4 for Gaussian noise excitation,
                                     // ~2 for a sine (sqrt 2 and margin); 0 disables the cap
  double rms_time_constant_s = 2.0;  // averaging of the variance and mean squares
  double statistics_hold_s = 20.0;   // release of the held gain g^2 and request ms(r)

  bool operator==(const BackoffConfig&) const = default;
};

// The back-off envelope of (2) above, one sample at a time.
class DeviationEnvelope {
 public:
  DeviationEnvelope(const BackoffConfig& config, double dt_s);
  double update(double deviation_kw);  // returns env_k
  double value() const { return envelope_kw_; }
  void reset();

 private:
  double dt_s_, decay_, w_r_;
  double b0_ = 0, b1_ = 0, b2_ = 0, a1_ = 0, a2_ = 0;  // low-pass biquad
  double x1_ = 0, x2_ = 0, y1_ = 0, y2_ = 0;
  bool primed_ = false;  // filter state initialised from the first sample
  double envelope_kw_ = 0.0;
};

// Layer 0: the governor applies what it is sent (DESIGN.md section 8).
struct EchoCheck {
  bool enabled = false;
  double tolerance_pct = safety_defaults::kEchoTolerancePct;            // absolute, % of rated
  double relative_tolerance = safety_defaults::kEchoRelativeTolerance;  // plus |command| share
  // The echo may lag the command this many ticks; consecutive mismatches allowed (one more
  // trips). Defaults: the test file's seconds at its default sample rate.
  int delay_ticks =
      safety_defaults::ticks_at(safety_defaults::kEchoDelayS, safety_defaults::kSampleRateHz);
  int max_bad_ticks =
      safety_defaults::ticks_at(safety_defaults::kEchoMaxBadS, safety_defaults::kSampleRateHz);

  bool operator==(const EchoCheck&) const = default;
};

// Readings that cannot be true of a running set.
struct PlausibilityCheck {
  bool speed = false;  // speed_rpm must stay > 0 (on when the steady state saw a speed)
  bool freq = false;   // freq_hz must stay > 0 (on when the steady state saw a frequency)

  bool operator==(const PlausibilityCheck&) const = default;
};

struct SupervisorConfig {
  double p0_kw = 0.0;  // steady power from the steady-state check
  // Defaults from rig/session/safety_defaults.hpp, shared with the test file's SafetySettings.
  double band_fraction = safety_defaults::kBandPct / 100.0;  // |P - P0| <= band_fraction P0;
                                                             // > 0.03 needs the override
  bool band_override = false;      // explicit permission for a band above 3 % (recorded)
  double baseline_bias_pct = 0.0;  // bias before excitation, the ramp's target
  double clamp_pct = safety_defaults::kClampPct;  // |bias| <= this, whatever the estimate
  double ramp_rate_pct_per_s = safety_defaults::kRampPctPerS;  // back to baseline (trip, end)
  double dt_s = 1.0 / safety_defaults::kSampleRateHz;          // tick period
  double noise_rms_kw = 0.0;  // power noise without excitation (steady-state check)
  // An unchanged counter for this many consecutive ticks trips (kStaleTimeoutS).
  int stale_ticks =
      safety_defaults::ticks_at(safety_defaults::kStaleTimeoutS, safety_defaults::kSampleRateHz);
  std::uint16_t trip_status_mask = drivers::kHeartbeatLost | drivers::kPlantFault;
  std::uint16_t required_status_mask = drivers::kRunning;  // a cleared bit here trips
  BackoffConfig backoff;
  EchoCheck echo;
  PlausibilityCheck plausible;

  double band_kw() const { return band_fraction * p0_kw; }
  bool operator==(const SupervisorConfig&) const = default;
};

// Throws SupervisorConfigError with a one-line message naming the field.
void validate(const SupervisorConfig& config);

struct TripRecord {
  TripCause cause = TripCause::kNone;
  std::string text;        // one line, e.g. "power 3612.0 kW is 112.0 kW from P0 (band 105.0)"
  std::uint64_t tick = 0;  // tick index at which it tripped
};

struct SupervisorOutput {
  double bias_pct = 0.0;        // write this
  double excitation_pct = 0.0;  // bias_pct - baseline: the excitation as applied (record as u)
  double scale = 0.0;           // back-off factor applied to the request, [0, 1]
  SupervisorState state = SupervisorState::kIdle;
  TripCause trip_cause = TripCause::kNone;  // latched
  std::uint16_t heartbeat = 0;
  double deviation_kw = 0.0;  // P - P0 of the judged sample (NaN when none)
  double envelope_kw = 0.0;   // back-off envelope
};

class Supervisor {
 public:
  explicit Supervisor(const SupervisorConfig& config);

  void start();   // idle -> running; the scale soft-starts from 0
  void finish();  // running/backing_off -> ramping_down (excitation over)
  // Latches a trip from outside the tick (write failure, operator abort); the next tick
  // ramps. A second trip keeps the first cause.
  void trip(TripCause cause, std::string text);

  SupervisorOutput tick(const drivers::Sample& sample, double request_pct);
  SupervisorOutput tick(const drivers::LinkResult<drivers::Sample>& read, double request_pct);
  SupervisorOutput tick_missing(double request_pct);  // no sample this tick

  SupervisorState state() const { return state_; }
  bool done() const { return state_ == SupervisorState::kDone; }
  bool tripped() const { return trip_.has_value(); }
  const std::optional<TripRecord>& trip_record() const { return trip_; }
  const SupervisorConfig& config() const { return config_; }
  bool band_overridden() const { return config_.band_fraction > kStandardBandPct / 100.0; }
  std::uint64_t ticks() const { return tick_; }

 private:
  bool active() const;
  void judge(const drivers::Sample& sample);
  std::string status_text(std::uint16_t status) const;
  void judge_echo(const drivers::Sample& sample);
  void judge_counter(const drivers::Sample& sample);
  SupervisorOutput command(double request_pct, double deviation_kw);
  double ramp_toward_baseline() const;

  SupervisorConfig config_;
  SupervisorState state_ = SupervisorState::kIdle;
  std::optional<TripRecord> trip_;
  std::uint64_t tick_ = 0;
  std::uint16_t heartbeat_ = 0;
  std::optional<std::uint16_t> last_counter_;
  int unchanged_ticks_ = 0;
  double statistical_cap() const;
  void update_statistics(double deviation_kw);

  DeviationEnvelope envelope_;
  double scale_ = 0.0;
  double mean_d_ = 0.0, ms_d_ = 0.0, ms_u_ = 0.0, ms_r_ = 0.0;  // exponentially weighted
  double ms_r_held_ = 0.0, g2_held_ = 0.0;
  double last_bias_pct_ = 0.0;
  static constexpr int kCommandHistory = 64;  // bound of echo.delay_ticks + 1
  double commands_[kCommandHistory] = {};     // ring of the last commands, newest at head_
  int head_ = 0, filled_ = 0, bad_echo_ticks_ = 0;
  bool counter_backwards_ = false;
};

}  // namespace rig::session
