// The endpoint strings of `plantsim --modbus` and `--can` (DESIGN.md section 4). They are
// link URIs without the family prefix, parsed by drivers::parse_link_uri so that the rig and
// plantsim read them with the same code:
//   --modbus tcp://HOST:PORT            (PORT 0 = ephemeral)
//   --modbus rtu:DEVICE?baud=19200[&parity=N|E|O][&unit=1]
//   --can    udp://HOST:PORT
//   --can    socketcan:IFACE
// Bad strings throw plantsim::ConfigError naming the option and what was expected.
#pragma once

#include <chrono>
#include <string>

#include "drivers/link_uri.hpp"

namespace plantsim::serve {

drivers::LinkUri parse_modbus_endpoint(const std::string& text);
drivers::LinkUri parse_can_endpoint(const std::string& text);

// "1ms", "500us", "0.002s", "250000ns"; within 100 us .. 1 s.
std::chrono::nanoseconds parse_tick(const std::string& text);

}  // namespace plantsim::serve
