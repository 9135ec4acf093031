#include "plantsim/serve/governor.hpp"

#include <algorithm>

#include "drivers/governor_link.hpp"

namespace plantsim::serve {

Governor::Governor(std::unique_ptr<Plant> plant, GovernorOptions options)
    : plant_(std::move(plant)),
      options_(options),
      tick_period_(plant_->tick()),
      rated_power_w_(plant_->rated_power_w()) {
  plant_->set_bias_pct(0.0);
  std::lock_guard lock(mu_);
  update_snapshot_locked();
}

void Governor::set_bias_pct(double bias_pct) {
  std::lock_guard lock(mu_);
  requested_pct_ = std::clamp(bias_pct, -options_.bias_limit_pct, options_.bias_limit_pct);
  snapshot_.bias_requested_pct = requested_pct_;
}

void Governor::set_enable(bool enable) {
  std::lock_guard lock(mu_);
  enabled_ = enable;
  snapshot_.enabled = enable;
}

void Governor::heartbeat(CommandSource source, std::uint32_t token) {
  std::lock_guard lock(mu_);
  auto& last = last_token_[static_cast<int>(source)];
  if (!last || *last != token) alive_at_ = snapshot_.plant_time;
  last = token;
}

void Governor::set_serve_faults(ServeFaultSchedule faults) {
  std::lock_guard lock(mu_);
  serve_faults_ = std::move(faults);
  update_snapshot_locked();
}

void Governor::tick() {
  {
    std::lock_guard lock(mu_);
    tick_locked();
  }
  ticked_.notify_all();
}

void Governor::advance(std::uint32_t ticks) {
  {
    std::lock_guard lock(mu_);
    for (std::uint32_t i = 0; i < ticks; ++i) tick_locked();
  }
  ticked_.notify_all();
}

// The gate is evaluated at the end time of the step about to be taken, t_end = t + T:
// lost when t_end - t_alive > timeout. t_alive is the plant time when the heartbeat last
// changed (<= the wall time of that write in realtime), so the bias is zero from the first
// tick ending more than 500 ms after the change: no earlier than 500 ms and no later than
// 500 ms + 1 tick after the rig's last heartbeat write.
void Governor::tick_locked() {
  const auto t_end = snapshot_.plant_time + tick_period_;
  const bool lost = !alive_at_ || (t_end - *alive_at_) > options_.heartbeat_timeout;
  const bool active = enabled_ && !lost;
  const double limit = std::min(options_.bias_limit_pct, plant_->external_bias_limit_pct());
  const double applied = active ? std::clamp(requested_pct_, -limit, limit) : 0.0;
  plant_->set_bias_pct(applied);
  plant_->step();
  snapshot_.heartbeat_lost = lost;
  snapshot_.bias_applied_pct = applied;
  update_snapshot_locked();
  for (const auto& listener : listeners_) listener(snapshot_);
}

void Governor::update_snapshot_locked() {
  auto& s = snapshot_;
  s.measurement = plant_->measure();
  s.ticks = plant_->ticks();
  s.plant_time = tick_period_ * static_cast<std::int64_t>(s.ticks);
  // A frozen counter stops at its value for the first tick the freeze is in force.
  if (serve_faults_.active(ServeFault::kFreezeCounter, s.plant_time)) {
    if (!s.frozen_counter) s.frozen_counter = static_cast<std::uint16_t>(s.ticks & 0xFFFFu);
  } else {
    s.frozen_counter.reset();
  }
  s.power_invalid = serve_faults_.active(ServeFault::kNanPower, s.plant_time);
  s.link_dropped = s.link_dropped || serve_faults_.active(ServeFault::kDropLink, s.plant_time);
  s.bias_requested_pct = requested_pct_;
  s.enabled = enabled_;
  const bool active = enabled_ && !s.heartbeat_lost;
  std::uint16_t status = 0;
  if (s.measurement.running) status |= drivers::kRunning;
  if (s.measurement.breaker_closed) status |= drivers::kBreakerClosed;
  if (active) status |= drivers::kBiasActive;
  if (s.heartbeat_lost) status |= drivers::kHeartbeatLost;
  if (s.measurement.fault) status |= drivers::kPlantFault;
  s.status = status;
}

GovernorSnapshot Governor::snapshot() const {
  std::lock_guard lock(mu_);
  return snapshot_;
}

void Governor::add_tick_listener(TickListener listener) {
  std::lock_guard lock(mu_);
  listeners_.push_back(std::move(listener));
}

bool Governor::wait_for_plant_time(std::chrono::nanoseconds t,
                                   std::chrono::steady_clock::time_point deadline) const {
  std::unique_lock lock(mu_);
  return ticked_.wait_until(lock, deadline, [&] { return snapshot_.plant_time >= t; });
}

}  // namespace plantsim::serve
