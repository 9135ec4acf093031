// Lockstep exchanges against a plantsim process, timed on the wall clock.
#pragma once

#include <string>
#include <vector>

namespace plantsim::bench {

struct ExchangeFigures {
  int exchanges = 0;
  double wall_s = 0.0;
  double simulated_s = 0.0;
  double p50_us = 0.0;  // one exchange (write, advance, read) round trip
  double p99_us = 0.0;
  double sim_per_wall() const { return wall_s > 0 ? simulated_s / wall_s : 0.0; }
};

// Modbus TCP at a 100 Hz exchange: write holding 0-2 (bias, heartbeat, enable), write holding
// 100 = 10, read input registers 0-9. `args` are extra plantsim arguments.
ExchangeFigures modbus_lockstep(const std::string& program, const std::vector<std::string>& args,
                                int exchanges);

// can+udp at a 100 Hz exchange: PGN 0xFF50 command, PGN 0xFF52 = 10, wait for the 10th 0xFF51.
ExchangeFigures can_lockstep(const std::string& program, const std::vector<std::string>& args,
                             int exchanges);

}  // namespace plantsim::bench
