// `plantsim --replay IN.csv --replay-out OUT.csv`: the plant's deterministic response to a
// recorded bias. The input is a CSV with a header row, a time column `t` (seconds, uniform)
// and the bias column (% of rated power); lines starting with '#' are skipped. The plant
// runs with its tick equal to the recording's sample period, starting at its operating
// point, with the random and nuisance parts of the measurement switched off (white noise,
// drift, mains pick-up, firing ripple, quantisation), so the output is the model's own
// response. Per row k: the bias u_k is applied, the measured power y_k at t_k is read, and
// the plant advances one tick (u_k held over [t_k, t_k+1), as a rig recording sees it).
// Output: `t,u,power_kw`.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "plantsim/plant/plant.hpp"

namespace plantsim {

struct ReplayInput {
  std::vector<double> t_s, bias_pct;
  double dt_s = 0.0;
};

// Throws ConfigError (one line naming the file, line and column) on a bad file.
ReplayInput read_replay_csv(const std::filesystem::path& file, const std::string& column);

// The parameter changes at t = 0 that switch the random/nuisance measurement parts off.
std::vector<std::string> deterministic_measurement_changes();

using PlantFactory = std::function<std::unique_ptr<Plant>(const PlantOptions&)>;

// Runs the plant (options with the tick replaced by the input's dt and the changes above
// appended) and returns the measured power in kW per row. Throws ConfigError on a bad
// configuration and std::runtime_error when the solver fails.
std::vector<double> replay(const ReplayInput& input, PlantOptions options,
                           const PlantFactory& make);

// Writes `t,u,power_kw` (ConfigError when the file cannot be written).
void write_replay_csv(const std::filesystem::path& file, const ReplayInput& input,
                      const std::vector<double>& power_kw);

}  // namespace plantsim
