// The governor-side protocol rules (DESIGN.md section 6) wrapped around a Plant: what a real
// electronic governor does with the rig's commands, independent of the transport.
//
//  * The external bias is applied only while the enable bit is set and the heartbeat is alive.
//  * Heartbeat: every transport reports its heartbeat token (Modbus holding 1, the 4-bit
//    counter of PGN 0xFF50). A token different from that transport's previous one marks the
//    rig alive at the current plant time t_alive. At every tick, after advancing, the heartbeat
//    is lost when t - t_alive > 500 ms; the applied bias is then zero and status bit 3 is set.
//    Because the check runs on plant time, the rule is the same in both clocks: in realtime
//    plant time follows the monotonic clock, so the bias drops within 500 ms + 1 tick of the
//    last change; in lockstep, 500 ms of *simulated* time without a heartbeat change drops it
//    (a rig that advances the plant without writing is a rig that has stopped).
//    Loss is not latched: the next heartbeat change re-applies the (freshly written) bias.
//    Until the first heartbeat the governor reports heartbeat lost.
//  * Commands received between ticks take effect at the next tick.
//  * Clamp: the applied bias is limited to +-min(GovernorOptions::bias_limit_pct,
//    Plant::external_bias_limit_pct()) (plant parameter gov.ext_bias_limit_pct, default 5 % of
//    rated, read at every tick so a --fault can change it); the echo reports the clamped value.
//
// Thread-safe: the clock thread ticks while the transport threads write and read.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "plantsim/plant/plant.hpp"
#include "plantsim/serve/serve_faults.hpp"

namespace plantsim::serve {

// Which transport a heartbeat token came from (each has its own previous token).
enum class CommandSource { kModbus = 0, kCan = 1, kTsc1 = 2 };

// The governor's outputs after a tick, ready for any transport to encode.
struct GovernorSnapshot {
  Measurement measurement;
  double bias_applied_pct = 0.0;    // what the governor applies (0 when disabled or lost; clamped)
  double bias_requested_pct = 0.0;  // as received (transport range only)
  bool enabled = false;
  bool heartbeat_lost = true;
  std::uint16_t status = 0;  // drivers::StatusBit flags
  std::uint64_t ticks = 0;   // ticks taken (the sample counter is its low 16 bits)
  std::chrono::nanoseconds plant_time{0};
  // Serve faults in force (serve_faults.hpp): the counter the transports publish while it is
  // frozen, power reported "not available", the link dropped.
  std::optional<std::uint16_t> frozen_counter;
  bool power_invalid = false;
  bool link_dropped = false;
  // The sample counter as published: ticks mod 2^16, or the frozen value.
  std::uint16_t counter() const {
    return frozen_counter ? *frozen_counter : static_cast<std::uint16_t>(ticks & 0xFFFFu);
  }
};

struct GovernorOptions {
  std::chrono::milliseconds heartbeat_timeout{500};
  // Transport range (int16 at 0.001 %/bit); the governor's own clamp is the plant's
  // external_bias_limit_pct() and the smaller of the two applies.
  double bias_limit_pct = 32.767;
};

class Governor {
 public:
  using TickListener = std::function<void(const GovernorSnapshot&)>;

  Governor(std::unique_ptr<Plant> plant, GovernorOptions options = {});

  // Rig commands from any transport.
  void set_bias_pct(double bias_pct);
  void set_enable(bool enable);
  void heartbeat(CommandSource source, std::uint32_t token);
  // Interface faults on plant time (--fault serve.*); set before serving starts.
  void set_serve_faults(ServeFaultSchedule faults);

  void tick();                        // one plant tick
  void advance(std::uint32_t ticks);  // lockstep: exactly `ticks` ticks, then return
  GovernorSnapshot snapshot() const;

  // Called after every tick with the lock held: keep it short (encode and send a frame).
  void add_tick_listener(TickListener listener);
  std::chrono::nanoseconds tick_period() const { return tick_period_; }
  double rated_power_w() const { return rated_power_w_; }

  // Blocks until plant time reaches `t` or `deadline` passes; true when reached.
  bool wait_for_plant_time(std::chrono::nanoseconds t,
                           std::chrono::steady_clock::time_point deadline) const;

 private:
  void tick_locked();
  void update_snapshot_locked();

  mutable std::mutex mu_;
  mutable std::condition_variable ticked_;
  std::unique_ptr<Plant> plant_;
  GovernorOptions options_;
  std::chrono::nanoseconds tick_period_;
  double rated_power_w_;
  double requested_pct_ = 0.0;
  bool enabled_ = false;
  std::optional<std::uint32_t> last_token_[3];
  std::optional<std::chrono::nanoseconds> alive_at_;  // plant time of the last heartbeat change
  GovernorSnapshot snapshot_;
  ServeFaultSchedule serve_faults_;
  std::vector<TickListener> listeners_;
};

}  // namespace plantsim::serve
