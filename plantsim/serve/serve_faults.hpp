// Faults of the governor's interfaces rather than of the plant (DESIGN.md section 8: stale
// or missing samples, link errors and NaN must trip the rig). They use the plant faults'
// syntax with a `serve.` prefix, on plant time:
//
//   --fault serve.freeze_counter=1@t=32   the sample counter (Modbus input 9, PGN 0xFF51
//                                         bytes 4-5) stops at its value at t while the plant
//                                         keeps running and every other value stays fresh
//   --fault serve.nan_power=1@t=32        the power reads "not available": Modbus input 0-1
//                                         = INT32_MIN, PGN 0xFF51 / GTACP power 0xFFFFFFFF
//   --fault serve.drop_link=1@t=32        the link is lost: Modbus closes the listener and
//                                         every connection; CAN stops sending and receiving
//
// VALUE is 1 (on) or 0 (off), so a fault can be a window: serve.nan_power=1@t=32 together
// with serve.nan_power=0@t=32.05. A fault is in force for every tick whose end time is at or
// after its `t`; the latest change at or before that time wins. The link drop is permanent
// (a listener once closed is not reopened).
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace plantsim::serve {

enum class ServeFault { kFreezeCounter = 0, kNanPower = 1, kDropLink = 2 };
inline constexpr int kServeFaultCount = 3;
const char* to_string(ServeFault fault);  // "serve.freeze_counter", ...

struct ServeFaultChange {
  ServeFault fault = ServeFault::kFreezeCounter;
  bool on = false;
  std::chrono::nanoseconds time{0};
  std::string text;  // as given
};

// True when `text` names a serve fault (starts with "serve.").
bool is_serve_fault(const std::string& text);

// Parses "serve.NAME=0|1@t=SECONDS"; throws plantsim::ConfigError with one line naming the
// fault string and what was expected.
ServeFaultChange parse_serve_fault(const std::string& text);

// Removes the serve faults from `faults` (the rest are plant parameter changes) and returns
// them parsed, sorted by time.
std::vector<ServeFaultChange> split_serve_faults(std::vector<std::string>& faults);

// Which serve faults are in force at a plant time.
class ServeFaultSchedule {
 public:
  ServeFaultSchedule() = default;
  explicit ServeFaultSchedule(std::vector<ServeFaultChange> changes);
  bool active(ServeFault fault, std::chrono::nanoseconds plant_time) const;
  bool empty() const { return changes_.empty(); }

 private:
  std::vector<ServeFaultChange> changes_;  // sorted by time
};

}  // namespace plantsim::serve
