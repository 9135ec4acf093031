// What the tick loop publishes on the live feed (rig/live/feed.hpp, docs/live.md) when a live
// page or a fleet feed is on: samples decimated to ~10 Hz of test time, the status at most
// every kStateIntervalS of wall time, events, and the loop timing every kTimingIntervalS.
// Without a feed every call returns at once.
#pragma once

#include <chrono>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "rig/live/feed.hpp"
#include "rig/session/live_view.hpp"
#include "rig/session/loop_timing.hpp"
#include "rig/session/supervisor.hpp"

namespace rig::session {

class LivePublisher {
 public:
  // A page redraws at its own pace; 5 states a second look live without flooding a feed.
  static constexpr double kStateIntervalS = 0.2;
  static constexpr double kTimingIntervalS = 2.0;
  static constexpr double kSampleRateHz = 10.0;  // the trace the report draws has the same

  LivePublisher(live::Feed* feed, double tick_rate_hz);

  bool on() const { return feed_ != nullptr; }
  void publish(const char* kind, const nlohmann::json& body) const;
  void sample(std::uint64_t tick, double t_s, double deviation_pct, double u_pct, int phase,
              bool backing_off);
  void state(const LiveStatus& status, SupervisorState supervisor, double p0_kw, bool force);
  void event(double t_s, const std::string& kind, const std::string& text) const;
  void timing(const LoopTimer& timer, double t_s, bool force = false);

 private:
  static bool due(std::chrono::steady_clock::time_point& last, double interval_s, bool force);

  live::Feed* feed_;
  std::uint64_t every_ticks_;
  std::chrono::steady_clock::time_point last_state_{}, last_timing_{};
  std::size_t timed_cycles_ = 0;  // cycles covered by the timing messages so far
};

}  // namespace rig::session
