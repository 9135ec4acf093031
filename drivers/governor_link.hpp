// GovernorLink: the rig's view of an electronic governor plus power transducer (DESIGN.md
// section 6). Lifecycle as in ros2_control's hardware_interface:
//   configure()  open the link, nothing energised
//   activate()   enable the external bias (control word bit 0 / CAN enable bit)
//   write(bias) / read()   one cycle; never throws, returns a status or an expected value
//   deactivate() ramp the bias to zero and clear the enable
//   close()
// Every cycle write also advances the heartbeat. Errors carry the register or frame and the
// OS/libmodbus text so that a one-line message can name what failed.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace drivers {

// Status bits reported by the governor (Modbus input register 6, CAN PGN 0xFF51 byte 6).
enum StatusBit : std::uint16_t {
  kRunning = 1u << 0,
  kBreakerClosed = 1u << 1,
  kBiasActive = 1u << 2,
  kHeartbeatLost = 1u << 3,
  kPlantFault = 1u << 4,
};

// One reading of the plant, in engineering units.
struct Sample {
  double plant_time_s = 0.0;  // governor/plant clock (input regs 7-8), 0 if unknown
  double power_kw = 0.0;      // electrical power
  double speed_rpm = 0.0;
  double freq_hz = 0.0;
  double voltage_v = 0.0;
  double bias_echo_pct = 0.0;  // bias as applied by the governor, % of rated power
  std::uint16_t status = 0;    // StatusBit flags
  std::uint16_t counter = 0;   // +1 per plant tick; a counter that does not move is stale
};

enum class LinkErrorKind {
  kTimeout,          // no answer within the response timeout
  kModbusException,  // the device answered with a Modbus exception
  kStale,            // the sample counter did not advance
  kChecksum,         // CAN checksum or counter error
  kLinkLost,         // connection closed, socket error, device gone
  kProtocol,         // malformed answer (wrong length, wrong unit, bad frame)
  kUnavailable,      // transport not supported on this host (e.g. no CAN in the kernel)
  kConfig,           // bad URI or parameters
};

struct LinkError {
  LinkErrorKind kind;
  std::string where;            // register / PGN / device, e.g. "holding 0" or "PGN 0xFF51"
  std::string detail;           // OS or libmodbus text
  std::string message() const;  // one line: "<kind> at <where>: <detail>"
};

const char* to_string(LinkErrorKind kind);

// A value or a LinkError (std::expected is C++23; this is the subset the links need).
template <class T>
class [[nodiscard]] LinkResult {
 public:
  LinkResult(T value) : v_(std::move(value)) {}          // NOLINT: implicit by design
  LinkResult(LinkError error) : v_(std::move(error)) {}  // NOLINT
  bool has_value() const { return v_.index() == 0; }
  explicit operator bool() const { return has_value(); }
  const T& value() const { return std::get<0>(v_); }
  T& value() { return std::get<0>(v_); }
  const T& operator*() const { return value(); }
  const T* operator->() const { return &value(); }
  const LinkError& error() const { return std::get<1>(v_); }

 private:
  std::variant<T, LinkError> v_;
};

template <>
class [[nodiscard]] LinkResult<void> {
 public:
  LinkResult() = default;
  LinkResult(LinkError error) : e_(std::move(error)) {}  // NOLINT
  bool has_value() const { return !e_.has_value(); }
  explicit operator bool() const { return has_value(); }
  const LinkError& error() const { return *e_; }

 private:
  std::optional<LinkError> e_;
};

class GovernorLink {
 public:
  virtual ~GovernorLink() = default;
  virtual LinkResult<void> configure() = 0;
  virtual LinkResult<void> activate() = 0;
  // Writes the bias (% of rated power, quantised to 0.001 %) and the heartbeat.
  virtual LinkResult<void> write(double bias_pct) = 0;
  virtual LinkResult<Sample> read() = 0;
  // Lockstep only (simulated plants): advance the plant by `ticks` before the next read.
  virtual LinkResult<void> advance(std::uint16_t ticks) = 0;
  // The bias the governor holds now, read back from the governor (Modbus: holding 0; CAN: the
  // last echo frame). The ramp-down starts from it, never from a stale value (DESIGN.md
  // section 8). The default says it cannot be read; callers then use what they last sent.
  virtual LinkResult<double> read_held_bias();
  virtual LinkResult<void> deactivate() = 0;
  virtual void close() = 0;
  virtual std::string uri() const = 0;
};

}  // namespace drivers
