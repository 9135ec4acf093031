// Link URIs of DESIGN.md section 6:
//   modbus+tcp://host:port?unit=1
//   modbus+rtu:/dev/ttyUSB0?baud=19200&unit=1&parity=N&data=8&stop=1
//   can+socketcan:can0
//   can+udp://127.0.0.1:29536
//   can+...?command=tsc1&sync_rpm=600   (command the governor with TSC1 instead of 0xFF50)
// Errors are kConfig LinkErrors whose `where` names the URI part (scheme, host, port, query
// key) and whose detail says what was expected.
#pragma once

#include <string>
#include <string_view>

#include "drivers/governor_link.hpp"

namespace drivers {

enum class LinkScheme { kModbusTcp, kModbusRtu, kCanSocketcan, kCanUdp };

// How a CAN link commands the governor: the proprietary 0xFF50 bias frame (default), or TSC1
// speed requests n = sync_rpm (1 + bias_pct / 100) for governors that accept only TSC1
// (coarser: 0.125 rpm/bit is 0.0208 % of bias at 600 rpm, against 0.001 % for 0xFF50).
enum class CanCommand { kBiasFrame, kTsc1 };

struct LinkUri {
  LinkScheme scheme = LinkScheme::kModbusTcp;
  std::string text;    // the URI as given (after adding a default family)
  std::string host;    // tcp/udp
  int port = 0;        // tcp/udp; 0 lets a listening side pick an ephemeral port
  std::string device;  // rtu: serial device path; socketcan: interface name
  int unit = 1;        // Modbus unit (slave) id, 0..247
  int baud = 19200;    // rtu
  char parity = 'N';   // rtu: N, E or O
  int data_bits = 8;   // rtu: 5..8
  int stop_bits = 1;   // rtu: 1 or 2
  CanCommand can_command = CanCommand::kBiasFrame;  // can: command=ff50|tsc1
  double sync_rpm = 0.0;                            // can, TSC1: synchronous speed

  bool is_modbus() const;
  bool is_can() const;
};

const char* to_string(LinkScheme scheme);  // "modbus+tcp", ...

// Parses a link URI. `default_family` ("modbus" or "can") is prefixed when the scheme has no
// family, so plantsim's `--modbus tcp://...` and `--can udp://...` parse with the same code.
LinkResult<LinkUri> parse_link_uri(std::string_view uri, std::string_view default_family = {});

}  // namespace drivers
