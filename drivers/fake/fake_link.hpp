// An in-process fake GovernorLink (DESIGN.md section 3, drivers/fake/), after ros2_control's
// mock components: no sockets, no threads, deterministic for a seed. It plays both the governor
// and the plant so that unit tests can drive every safety rule of the session (DESIGN.md
// section 8) in microseconds; its own log of what the governor saw is the judge.
//
// Plant: P = p0 + G(s) e^(-s delay_s) b_applied + noise (+ faults), with
//   G(s) = K wn^2 / (s^2 + 2 zeta wn s + wn^2), K = gain_kw_per_pct, wn = 2 pi fn_hz,
// discretised exactly (zero-order hold) at dt_s; |G(j wn)| = K / (2 zeta). fn_hz = 0 gives the
// static gain K (no dynamics). The dead time is round(delay_s / dt_s) samples, so a bias written
// between the reads of t and t + dt first shows in the sample of t + delay + dt.
// Clock: one plant tick is one sample of dt_s (the counter moves +1 per tick).
//   lockstep (options.lockstep): the plant moves only on advance(n), by n ticks;
//   realtime: every read() (a failing one too) first advances one tick; advance() does nothing.
//   The stale rule is CounterCheck's, run on plant time, so it is deterministic in both clocks.
// Governor rules:
//   * holding 0 (held_bias_pct) is the last accepted command, quantised by quantise_bias;
//     write() keeps the enable bit, activate() writes {0, enable}, disable() {0, no enable};
//   * honoured = enabled, heartbeat alive, not ignore_bias, at or after honour_after_s; then
//     applied = clamp(held * echo_scale * apply_scale, +-governor_clamp_pct),
//     echo = clamp(held * echo_scale), status kBiasActive; else applied = echo = 0;
//   * every accepted write is a heartbeat. Enabled with no write for more than 0.5 s of plant
//     time (judged at the end of each tick, so the bias drops on the first tick ending more than
//     0.5 s after the last write): applied = echo = 0 and kHeartbeatLost, until the next write;
//   * a write takes effect at once (applied_bias_pct, the next read's echo and status); the
//     plant sees it from the next tick on, after the dead time.
// Faults are in force from their plant time on (t_s() >= time). The link drop happens once:
// from then every call fails with kLinkLost until a configure() succeeds (after
// reconnects_refused refusals). A refused write (kModbusException) changes nothing; a late one
// (kTimeout) is applied. read_timeout_after_s affects read() only. Plant time and the
// governor's registers survive configure()/close(): a reconnect finds the governor as it was.
// deactivate() is LinkBase's ramp through write(), so the write log records it.
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "drivers/governor_link.hpp"
#include "drivers/link_base.hpp"
#include "drivers/link_options.hpp"

namespace drivers::fake {

struct FakePlant {        // discrete bias-to-power plant, advanced one sample per exchange
  double p0_kw = 3500.0;  // steady power
  double gain_kw_per_pct = 46.0;
  double fn_hz = 2.0, zeta = 0.1;  // second-order mode (0 fn: first-order-free static gain)
  double delay_s = 0.06;           // pure dead time
  double noise_kw = 5.0;           // white measurement noise rms
  double dt_s = 0.01;              // one sample per exchange
  std::uint64_t seed = 1;
  double speed_rpm = 600.0, freq_hz = 50.0, voltage_v = 11000.0;
};

struct FakeFaults {          // each fault acts from its time (plant seconds since configure())
  bool ignore_bias = false;  // enable never honoured: no bias active bit, echo 0
  std::optional<double> honour_after_s;  // bias honoured (and echoed) only from this time on
  double echo_scale = 1.0;               // the governor applies and echoes bias * echo_scale
  double apply_scale = 1.0;  // applies bias * apply_scale but echoes the command (a lying echo)
  std::optional<double> refuse_writes_after_s;  // writes return kModbusException, nothing applied
  std::optional<double> late_writes_after_s;    // writes return kTimeout but ARE applied
  std::optional<double> drop_after_s;  // from then every call returns kLinkLost until configure()
  int reconnects_refused = 0;          // that many configure() calls after a drop fail (kLinkLost)
  std::optional<double> freeze_counter_after_s;  // counter stops moving
  std::optional<double> nan_power_after_s;       // power NaN
  std::optional<double> power_jump_after_s;      // step in P
  double power_jump_kw = 0.0;
  std::optional<double> read_timeout_after_s;  // reads return kTimeout
  double governor_clamp_pct = 5.0;             // the governor clamps the external bias it applies
  bool heartbeat_rule = true;  // bias dropped (step) when the heartbeat stops for 500 ms
};

struct WriteRecord {  // every write attempt the governor saw
  double t_s;
  double bias_pct;
  bool enable;
  bool accepted;
};

class FakeGovernorLink : public LinkBase {
 public:
  explicit FakeGovernorLink(FakePlant plant = {}, FakeFaults faults = {}, LinkOptions options = {});
  FakeGovernorLink(const FakeGovernorLink&) = delete;
  FakeGovernorLink& operator=(const FakeGovernorLink&) = delete;

  LinkResult<void> configure() override;
  LinkResult<void> activate() override { return send(0.0, true, "holding 0-2"); }
  LinkResult<void> write(double bias_pct) override {
    return send(bias_pct, enable_, "holding 0-1");
  }
  LinkResult<Sample> read() override;
  LinkResult<void> advance(std::uint16_t ticks) override;
  LinkResult<double> read_held_bias() override;
  void close() override { configured_ = false; }
  std::string uri() const override { return "fake://governor"; }

  // Introspection for tests (the fake's own log is the judge).
  const std::vector<WriteRecord>& writes() const { return writes_; }
  double applied_bias_pct() const { return applied_pct_; }  // what the governor applies now
  double held_bias_pct() const { return held_pct_; }        // holding 0: the last accepted command
  bool enabled() const { return enable_; }                  // the control word's enable bit
  double t_s() const { return static_cast<double>(ticks_) * plant_.dt_s; }  // plant time
  int configure_calls() const { return configure_calls_; }

 protected:
  LinkResult<void> disable() override { return send(0.0, false, "holding 0-2"); }

 private:
  LinkResult<void> send(double bias_pct, bool enable, const char* where);
  void check_drop();
  std::optional<LinkError> unusable(const std::string& where);  // not configured or dropped
  bool in_force(const std::optional<double>& from_s) const;
  void update_governor();
  void tick();
  Sample sample() const;

  FakePlant plant_;
  FakeFaults faults_;
  CounterCheck counter_;
  // Plant: x = {y, dy/dt} with y the response in kW; x(k+1) = phi x(k) + gamma u(k - delay).
  double phi_[2][2] = {{1.0, 0.0}, {0.0, 1.0}};
  double gamma_[2] = {0.0, 0.0};
  double x_[2] = {0.0, 0.0};
  std::vector<double> delay_line_;  // ring of the last round(delay_s / dt_s) applied biases
  std::size_t delay_pos_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  double noise_now_kw_ = 0.0;
  std::uint64_t ticks_ = 0;
  std::optional<std::uint16_t> frozen_counter_;
  // Governor.
  double held_pct_ = 0.0;
  bool enable_ = false;
  std::uint64_t alive_tick_ = 0;  // tick of the last accepted write (heartbeat)
  std::uint64_t heartbeat_ticks_ = 50;
  bool honoured_ = false, heartbeat_lost_ = false;
  double applied_pct_ = 0.0, echo_pct_ = 0.0;
  // Link.
  bool configured_ = false, drop_fired_ = false, dropped_ = false;
  int refusals_left_ = 0;
  int configure_calls_ = 0;
  std::vector<WriteRecord> writes_;
};

}  // namespace drivers::fake
