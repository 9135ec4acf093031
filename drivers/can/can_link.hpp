// GovernorLink over CAN (can+udp or can+socketcan) with the J1939 map of j1939.hpp.
//   configure()  open the endpoint (client role)
//   activate()   0xFF50 {bias 0, enable}
//   write(b)     0xFF50 {bias, enable as activated, counter+1}: the counter is the heartbeat
//   advance(n)   0xFF52 {n} (sim only, the CAN equivalent of Modbus holding 100)
//   read()       waits for the 0xFF51 frame of a new plant tick (after advance(n): the tick
//                counter + n), then drains frames already queued so the sample is the latest;
//                EEC1 fills speed_rpm and GTACP/0xFF51 fill power_kw as they arrive.
//                Frames from other source addresses are ignored.
//   deactivate() ramp, then 0xFF50 {0, enable cleared}
// With ?command=tsc1&sync_rpm=N the commands go out as TSC1 speed requests instead (see
// CanCommand in link_uri.hpp); the heartbeat is TSC1's own 4-bit counter.
// CAN carries no frequency, voltage or bias echo: those Sample fields stay 0. plant_time_s is
// counter * LinkOptions::plant_tick when that is set (the counter is unwrapped past 65535).
#pragma once

#include <memory>

#include "drivers/link_base.hpp"
#include "drivers/link_uri.hpp"

namespace drivers {

std::unique_ptr<GovernorLink> make_can_link(const LinkUri& uri, const LinkOptions& options);

}  // namespace drivers
