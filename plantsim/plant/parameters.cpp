#include "plantsim/plant/parameters.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "plantsim/plant/plant.hpp"

namespace plantsim {

const std::array<ParamSpec, kParamCount>& param_specs() {
  static const std::array<ParamSpec, kParamCount> specs{{
#define X(id, name, unit, def, lo, hi, doc) ParamSpec{name, unit, def, lo, hi, doc},
      PLANTSIM_PARAMETERS
#undef X
  }};
  return specs;
}

const ParamSpec& spec(P id) { return param_specs()[static_cast<std::size_t>(id)]; }

bool rampable(P id) {
  const ParamSpec& s = spec(id);
  return s.unit != "bool" && id != P::kEngCylinders && id != P::kAltE &&
         s.name.substr(0, 7) != "solver.";
}

std::optional<P> find_param(std::string_view name) {
  const auto& specs = param_specs();
  std::optional<P> match;
  int suffix_matches = 0;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const std::string_view full = specs[i].name;
    if (full == name) return static_cast<P>(i);
    const auto dot = full.find('.');
    if (name.find('.') == std::string_view::npos && full.substr(dot + 1) == name) {
      match = static_cast<P>(i);
      ++suffix_matches;
    }
  }
  if (suffix_matches == 1) return match;
  return std::nullopt;
}

Params::Params() {
  const auto& specs = param_specs();
  for (std::size_t i = 0; i < specs.size(); ++i) v_[i] = specs[i].default_value;
}

void Params::set(P id, double value, const std::string& where) {
  const ParamSpec& s = spec(id);
  if (!std::isfinite(value) || value < s.min_value || value > s.max_value) {
    throw ConfigError(fmt::format("{}: {} = {} out of range, expected {} .. {} {}", where, s.name,
                                  value, s.min_value, s.max_value, s.unit));
  }
  v_[static_cast<std::size_t>(id)] = value;
}

double Params::injector(int cylinder_index) const {
  // Cylinders 1..floor(injectors_out) are cut completely, the next one by the fraction left;
  // the others keep their own health.
  const double cut = std::clamp((*this)[P::kEngInjectorsOut] - cylinder_index, 0.0, 1.0);
  const auto base = static_cast<std::size_t>(P::kInjector1);
  return (1.0 - cut) * v_[base + static_cast<std::size_t>(cylinder_index)];
}

}  // namespace plantsim
