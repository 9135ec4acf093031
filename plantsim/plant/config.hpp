// Plant configuration: named presets, the plant TOML (--config) and timed parameter changes
// (--fault NAME=VALUE@t=SECONDS[,ramp=SECONDS]). Every error is a ConfigError with one line naming
// the file/key or fault string and what was expected.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "plantsim/plant/parameters.hpp"
#include "plantsim/plant/plant.hpp"

namespace plantsim {

struct TimedChange {
  P param;
  double value = 0.0;
  double time_s = 0.0;
  double ramp_s = 0.0;  // > 0: linear from the value at time_s to `value` at time_s + ramp_s
  std::string text;     // as given, for messages
};

std::vector<std::string> preset_names();
Params preset(const std::string& name);  // throws ConfigError for an unknown name

// Reads a plant TOML: an optional top-level `preset = "name"` (the base; defaults otherwise)
// and one table per block ([gov], [engine], ...) whose keys are parameter names.
Params load_toml(const std::filesystem::path& file);
// The same from text; `origin` names the source in messages.
Params parse_toml(const std::string& text, const std::string& origin);

// "NAME=VALUE@t=SECONDS" (NAME dotted or a unique bare name, e.g. injector_3=0@t=20), or
// "NAME=VALUE@t=SECONDS,ramp=SECONDS": from the value at t linearly to VALUE over the ramp
// time (ramp=0 is abrupt). Switches, engine.cylinders, alt.e_pu and solver.* take no ramp.
TimedChange parse_change(const std::string& text);

// Writes every parameter as plant TOML, one table per block, each line commented with its
// unit, meaning and valid range (what plantsim/presets/*.toml contain). `header` lines are
// prepended as comments.
std::string to_toml(const Params& params, const std::string& header);

// Resolves PlantOptions into parameters and time-sorted changes (validated against ranges).
struct ResolvedConfig {
  Params params;
  std::vector<TimedChange> changes;
};
ResolvedConfig resolve(const PlantOptions& options);

}  // namespace plantsim
