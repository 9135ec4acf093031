// GovernorLink over Modbus TCP or RTU (libmodbus), register map in register_map.hpp.
//   configure()  modbus_new_tcp/modbus_new_rtu, unit id, response timeout, connect
//   activate()   holding 0..2 = {bias 0, heartbeat+1, enable}
//   write(b)     holding 0..1 = {bias, heartbeat+1} in one function-16 request
//   read()       input 0..9 (function 04) -> Sample, counter rule of CounterCheck
//   advance(n)   holding 100 = n (sim only)
//   deactivate() ramp, then holding 0..2 = {0, heartbeat+1, 0}
// libmodbus errno values (EMBX* exceptions, ETIMEDOUT, socket errors) become LinkErrors in
// one place, modbus_error() in modbus_link.cpp.
#pragma once

#include <memory>
#include <string>

#include "drivers/link_base.hpp"
#include "drivers/link_uri.hpp"

namespace drivers {

// The one translation of a libmodbus failure (errno `err`) at register range `where`.
LinkError modbus_error(int err, const std::string& where);

std::unique_ptr<GovernorLink> make_modbus_link(const LinkUri& uri, const LinkOptions& options);

}  // namespace drivers
