#include "drivers/fake/fake_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "drivers/bias.hpp"

namespace drivers::fake {

namespace {

constexpr double kHeartbeatTimeoutS = 0.5;
constexpr double kTimeEpsilonS = 1e-9;  // t_s() is ticks * dt_s: 0.3 may come out 0.2999...

double quantised(double bias_pct) { return bias_from_raw(quantise_bias(bias_pct)); }

// Zero-order-hold discretisation of x' = A x + b u, A = [0 1; -wn^2 -2 zeta wn],
// b = [0; K wn^2]. With m = tr(A)/2 and B = A - m I, B^2 = d I (d = m^2 - det A), so
// exp(A T) = e^(m T) (c I + s B) with c, s the cosh/sinh (d > 0), cos/sin (d < 0) or 1, T
// (d = 0) of sqrt(|d|) T; and gamma = A^-1 (phi - I) b.
void discretise(const FakePlant& p, double phi[2][2], double gamma[2]) {
  const double wn = 2.0 * std::numbers::pi * p.fn_hz;
  const double a[2][2] = {{0.0, 1.0}, {-wn * wn, -2.0 * p.zeta * wn}};
  const double m = -p.zeta * wn;
  const double d = m * m - wn * wn;
  const double t = p.dt_s;
  double c = 1.0, s = t;
  if (d > 0.0) {
    const double r = std::sqrt(d);
    c = std::cosh(r * t);
    s = std::sinh(r * t) / r;
  } else if (d < 0.0) {
    const double r = std::sqrt(-d);
    c = std::cos(r * t);
    s = std::sin(r * t) / r;
  }
  const double e = std::exp(m * t);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      phi[i][j] = e * ((i == j ? c : 0.0) + s * (a[i][j] - (i == j ? m : 0.0)));
    }
  }
  const double b1 = p.gain_kw_per_pct * wn * wn;
  const double v0 = phi[0][1] * b1;  // (phi - I) b
  const double v1 = (phi[1][1] - 1.0) * b1;
  const double det = wn * wn;  // A^-1 = [a11 -a01; -a10 a00] / det
  gamma[0] = (a[1][1] * v0 - a[0][1] * v1) / det;
  gamma[1] = (-a[1][0] * v0 + a[0][0] * v1) / det;
}

}  // namespace

FakeGovernorLink::FakeGovernorLink(FakePlant plant, FakeFaults faults, LinkOptions options)
    : LinkBase(options), plant_(plant), faults_(faults), counter_(options_), rng_(plant.seed) {
  if (plant_.fn_hz > 0.0) discretise(plant_, phi_, gamma_);
  const auto delay = std::llround(std::max(plant_.delay_s, 0.0) / plant_.dt_s);
  delay_line_.assign(static_cast<std::size_t>(delay), 0.0);
  heartbeat_ticks_ = static_cast<std::uint64_t>(std::llround(kHeartbeatTimeoutS / plant_.dt_s));
  if (plant_.noise_kw > 0.0) noise_now_kw_ = plant_.noise_kw * gauss_(rng_);
}

bool FakeGovernorLink::in_force(const std::optional<double>& from_s) const {
  return from_s && t_s() + kTimeEpsilonS >= *from_s;
}

void FakeGovernorLink::check_drop() {
  if (!drop_fired_ && in_force(faults_.drop_after_s)) {
    drop_fired_ = dropped_ = true;
    refusals_left_ = faults_.reconnects_refused;
  }
}

std::optional<LinkError> FakeGovernorLink::unusable(const std::string& where) {
  if (!configured_) return not_configured(where);
  check_drop();
  if (dropped_) {
    return LinkError{LinkErrorKind::kLinkLost, where, "connection reset by peer (fake: drop)"};
  }
  return std::nullopt;
}

// After a drop, calls keep failing with kLinkLost until a configure() succeeds.
LinkResult<void> FakeGovernorLink::configure() {
  ++configure_calls_;
  check_drop();  // a drop due now happens before the reconnect
  if (dropped_ && refusals_left_ > 0) {
    --refusals_left_;
    return LinkError{LinkErrorKind::kLinkLost, uri() + " connect",
                     "connection refused (fake: reconnects_refused)"};
  }
  configured_ = true;
  dropped_ = false;
  counter_.reset();
  return {};
}

// The one write path: activate(), write(), disable() and so deactivate()'s ramp.
LinkResult<void> FakeGovernorLink::send(double bias_pct, bool enable, const char* where) {
  if (auto e = unusable(where)) return *e;
  const double bias = quantised(bias_pct);
  last_sent_pct_ = bias;
  const bool refused = in_force(faults_.refuse_writes_after_s);
  writes_.push_back(WriteRecord{t_s(), bias, enable, !refused});
  if (refused) {
    return LinkError{LinkErrorKind::kModbusException, where,
                     "Slave device or server failure (exception 4) (fake: refuse_writes)"};
  }
  held_pct_ = bias;
  enable_ = enable;
  alive_tick_ = ticks_;
  update_governor();
  if (in_force(faults_.late_writes_after_s)) {
    return LinkError{LinkErrorKind::kTimeout, where, "Connection timed out (fake: late_writes)"};
  }
  last_bias_pct_ = bias;
  return {};
}

void FakeGovernorLink::update_governor() {
  heartbeat_lost_ = faults_.heartbeat_rule && enable_ && ticks_ - alive_tick_ > heartbeat_ticks_;
  honoured_ = enable_ && !heartbeat_lost_ && !faults_.ignore_bias &&
              (!faults_.honour_after_s || in_force(faults_.honour_after_s));
  const double limit = std::abs(faults_.governor_clamp_pct);
  auto clamp = [&](double v) { return std::clamp(v, -limit, limit); };
  applied_pct_ = honoured_ ? clamp(held_pct_ * faults_.echo_scale * faults_.apply_scale) : 0.0;
  echo_pct_ = honoured_ ? quantised(clamp(held_pct_ * faults_.echo_scale)) : 0.0;
}

// One plant tick: the governor is judged at the tick's end time, then the plant integrates
// over the tick with the bias it applies (zero-order hold), delayed by the dead time.
void FakeGovernorLink::tick() {
  ++ticks_;
  update_governor();
  double u = applied_pct_;
  if (!delay_line_.empty()) {
    std::swap(u, delay_line_[delay_pos_]);
    delay_pos_ = (delay_pos_ + 1) % delay_line_.size();
  }
  if (plant_.fn_hz > 0.0) {
    const double y = phi_[0][0] * x_[0] + phi_[0][1] * x_[1] + gamma_[0] * u;
    x_[1] = phi_[1][0] * x_[0] + phi_[1][1] * x_[1] + gamma_[1] * u;
    x_[0] = y;
  } else {
    x_[0] = plant_.gain_kw_per_pct * u;
  }
  noise_now_kw_ = plant_.noise_kw > 0.0 ? plant_.noise_kw * gauss_(rng_) : 0.0;
  if (!in_force(faults_.freeze_counter_after_s)) {
    frozen_counter_.reset();
  } else if (!frozen_counter_) {
    frozen_counter_ = static_cast<std::uint16_t>(ticks_ & 0xFFFFu);
  }
}

Sample FakeGovernorLink::sample() const {
  Sample s;
  s.plant_time_s = t_s();
  s.power_kw = plant_.p0_kw + x_[0] + noise_now_kw_;
  if (in_force(faults_.power_jump_after_s)) s.power_kw += faults_.power_jump_kw;
  if (in_force(faults_.nan_power_after_s)) s.power_kw = std::numeric_limits<double>::quiet_NaN();
  s.speed_rpm = plant_.speed_rpm;
  s.freq_hz = plant_.freq_hz;
  s.voltage_v = plant_.voltage_v;
  s.bias_echo_pct = echo_pct_;
  s.status = kRunning | kBreakerClosed;
  if (honoured_) s.status |= kBiasActive;
  if (heartbeat_lost_) s.status |= kHeartbeatLost;
  s.counter = frozen_counter_ ? *frozen_counter_ : static_cast<std::uint16_t>(ticks_ & 0xFFFFu);
  return s;
}

LinkResult<Sample> FakeGovernorLink::read() {
  const std::string where = "input 0-9";
  if (configured_ && !options_.lockstep) tick();  // realtime: time passes, answer or not
  if (auto e = unusable(where)) return *e;
  if (in_force(faults_.read_timeout_after_s)) {
    return LinkError{LinkErrorKind::kTimeout, where, "Connection timed out (fake: read_timeout)"};
  }
  Sample s = sample();
  // The stale rule on plant time: deterministic, and the same in both clocks.
  const auto now =
      CounterCheck::Clock::time_point{} + std::chrono::duration_cast<CounterCheck::Clock::duration>(
                                              std::chrono::nanoseconds(std::llround(t_s() * 1e9)));
  if (auto r = counter_.check(s.counter, now, "input 9"); !r) return r.error();
  return s;
}

LinkResult<void> FakeGovernorLink::advance(std::uint16_t ticks) {
  if (auto e = unusable("holding 100")) return *e;
  if (!options_.lockstep || ticks == 0) return {};  // a realtime plant ignores holding 100
  for (std::uint16_t i = 0; i < ticks; ++i) tick();
  counter_.expect_ticks(ticks);
  return {};
}

// As the Modbus link: the echo, what the governor applies now (after a heartbeat loss it has
// dropped the bias though holding 0 still holds it; the ramp must not re-apply that).
LinkResult<double> FakeGovernorLink::read_held_bias() {
  if (auto e = unusable("input 5")) return *e;
  return applied_pct_;
}

}  // namespace drivers::fake
