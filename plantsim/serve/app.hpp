// The `plantsim` program (DESIGN.md section 4) as a library function so the executable stays
// thin: parse the command line, build the plant, open the endpoints (nothing is started until
// every endpoint opened), serve until SIGINT/SIGTERM or --duration of plant time, then stop
// the threads and close the sockets.
//
// Exit codes: 0 clean stop, 2 usage/config/input error (one line on stderr naming the option,
// file, key or resource and what was expected), 3 a transport failed while serving.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "plantsim/plant/plant.hpp"
#include "plantsim/serve/can_node.hpp"
#include "plantsim/serve/modbus_node.hpp"
#include "plantsim/serve/serve_faults.hpp"

namespace plantsim::serve {

struct PlantHooks {
  std::function<std::unique_ptr<Plant>(const PlantOptions&)> make_plant;
  // Writes the linearised transfer-function JSON; empty when this build cannot.
  std::function<void(const PlantOptions&, const std::filesystem::path&)> linearise;
  // Every parameter of the resolved preset/config as commented plant TOML; empty if unknown.
  std::function<std::string(const PlantOptions&)> list_params;
};

struct ServeOptions {
  PlantOptions plant;                        // plant.faults: parameter changes only
  std::vector<ServeFaultChange> serve_faults;  // --fault serve.* (serve_faults.hpp)
  std::optional<std::string> modbus;  // endpoint text; default tcp://127.0.0.1:1502 if no --can
  std::optional<std::string> can;
  CanNodeOptions can_node;  // --can-rig-address, --can-sample-period
  ClockMode clock = ClockMode::kRealtime;
  std::optional<double> duration_s;  // stop at this plant time
  bool readout = false;
  std::optional<std::filesystem::path> linearise_to;
  bool list_params = false;
  // --replay IN.csv --replay-out OUT.csv [--replay-column NAME] (plantsim/plant/replay.hpp)
  std::optional<std::filesystem::path> replay_in, replay_out;
  std::string replay_column = "u";
};

// Returns the exit code.
int plantsim_main(int argc, char** argv, const PlantHooks& hooks);
int serve(const ServeOptions& options, const PlantHooks& hooks);

}  // namespace plantsim::serve
