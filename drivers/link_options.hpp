// Options shared by every GovernorLink implementation (DESIGN.md section 6).
#pragma once

#include <chrono>
#include <cstdint>

namespace drivers {

struct LinkOptions {
  // A request (Modbus) or the next plant tick (CAN) must arrive within this.
  std::chrono::milliseconds response_timeout{200};
  // Realtime clock: a read whose sample counter has not moved for this long is kStale.
  std::chrono::milliseconds stale_timeout{100};
  // Lockstep clock: the plant only ticks on advance(); the wall-clock stale rule is off and a
  // read after advance(n) must see the counter move by exactly n.
  bool lockstep = false;
  // deactivate(): ramp the bias to zero at this rate, one write per step; each step waits
  // ramp_period (realtime) or advances the plant ramp_ticks_per_step ticks (lockstep).
  double ramp_rate_pct_per_s = 2.0;
  std::chrono::milliseconds ramp_period{20};
  std::uint16_t ramp_ticks_per_step = 20;
  // CAN only: plant tick, to derive Sample::plant_time_s from the sample counter (0: unknown).
  std::chrono::microseconds plant_tick{0};
};

}  // namespace drivers
