// The emulated generator set as the servers see it (DESIGN.md section 7): a plant that is
// stepped one tick at a time, takes the governor setpoint bias and reports what a power
// transducer and speed pick-up would. The servers in plantsim/serve/ own the governor-side
// protocol rules (heartbeat, enable bit); the plant only integrates the physics.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace plantsim {

// A configuration error (unknown preset or parameter, out-of-range value, malformed TOML,
// malformed --fault): what() is one line naming the file/key and what was expected.
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Measurement {
  double time_s = 0.0;   // plant time
  double power_w = 0.0;  // measured electrical power (after the measurement chain)
  double speed_rpm = 0.0;
  double freq_hz = 0.0;           // bus frequency
  double voltage_v = 0.0;         // terminal voltage
  double bias_applied_pct = 0.0;  // bias the governor is applying, % of rated power
  bool running = true;
  bool breaker_closed = true;
  bool fault = false;  // solver failure or a plant-side fault state
};

class Plant {
 public:
  virtual ~Plant() = default;
  // Governor setpoint bias in % of rated power (already zero when the enable bit is clear).
  virtual void set_bias_pct(double bias_pct) = 0;
  // Advance exactly one tick.
  virtual void step() = 0;
  virtual Measurement measure() const = 0;
  virtual std::chrono::nanoseconds tick() const = 0;
  virtual std::uint64_t ticks() const = 0;  // ticks taken so far
  virtual double rated_power_w() const = 0;
  // The governor's clamp on the external bias, % of rated power (parameter
  // gov.ext_bias_limit_pct): the serving layer applies and echoes at most this much.
  virtual double external_bias_limit_pct() const { return kDefaultExternalBiasLimitPct; }
  static constexpr double kDefaultExternalBiasLimitPct = 5.0;
};

struct PlantOptions {
  std::string preset = "stornoway";             // ignored when `config` is set
  std::optional<std::filesystem::path> config;  // plant TOML
  std::vector<std::string> faults;              // "NAME=VALUE@t=SECONDS[,ramp=SECONDS]"
  std::uint64_t seed = 1;
  std::chrono::nanoseconds tick = std::chrono::milliseconds(1);
};

// Builds the plant; throws ConfigError on any bad input.
std::unique_ptr<Plant> make_plant(const PlantOptions& options);

}  // namespace plantsim
