// Named presets. `stornoway` is the ground-truth plant of the identification tests
// (DESIGN.md section 7, MMFM.md section 1); plantsim/presets/stornoway.toml is the same
// preset written out with units and is checked against this table by test_plant_preset.
#include <fmt/format.h>

#include <utility>

#include "plantsim/plant/config.hpp"

namespace plantsim {
namespace {

using Overrides = std::vector<std::pair<P, double>>;

// 4.6 MW, 600 rpm, 12 cylinders, 50 Hz, grid-connected at 3.5 MW. Tuned so that the
// bias-to-power response has its electromechanical mode at about 2.0 Hz with damping ratio
// about 0.1 and a fuel dead time 30/N + 60/(n N) = 58 ms:
//  * swing mode: w_n^2 = Ks w_b / 2H with Ks = E'V cos(d0)/X = 2.06 pu (X = 0.5 pu,
//    d0 = 20 deg), H = 2 s -> 2.0 Hz; 2 zeta w_n ~ (D - P0)/2H -> D = 11 pu for zeta ~ 0.1.
//  * governor as a kW controller: TE = T4 and R K T4 = 1 make the power loop's closed-loop
//    gain flat (1 % bias -> 1 % power at all frequencies below the mode), and the speed
//    error has a small weight (0.05) so that the delayed speed loop barely reshapes the mode.
//  * small actuator/control-box lags keep the apparent SOPDT delay near 80 ms.
const Overrides& stornoway() {
  static const Overrides o = {
      {P::kRatedKw, 4600.0},    {P::kPowerKw, 3500.0},
      {P::kFreqHz, 50.0},       {P::kGridConnected, 1.0},
      {P::kGovR, 0.05},         {P::kGovTe, 5.0},
      {P::kGovSpeedGain, 0.05}, {P::kGovT1, 0.2},
      {P::kGovT2, 0.003},       {P::kGovT3, 0.2},
      {P::kGovK, 4.0},          {P::kGovT4, 5.0},
      {P::kGovT5, 0.004},       {P::kGovT6, 0.002},
      {P::kGovTmin, 0.0},       {P::kGovTmax, 1.1},
      {P::kEngRpm, 600.0},      {P::kEngCylinders, 12.0},
      {P::kEngDeadTime, 0.0},   {P::kEngCombustionLag, 0.008},
      {P::kEngBoostLag, 2.0},   {P::kAltH, 2.0},
      {P::kAltD, 11.0},         {P::kAltE, 1.1},
      {P::kAltXdp, 0.25},       {P::kGridXe, 0.25},
      {P::kGridV, 1.0},         {P::kMeasLag, 0.003},
      {P::kMeasNoise, 5.0},     {P::kMeasPickup, 3.0},
      {P::kMeasDrift, 5.0},     {P::kMeasDriftTau, 60.0},
      {P::kMeasQuant, 1.0},
  };
  return o;
}

// The same set islanded on a 3.5 MW frequency-dependent load, with full DEGOV1 speed weight.
const Overrides& stornoway_island() {
  static const Overrides o = [] {
    Overrides v = stornoway();
    v.push_back({P::kGridConnected, 0.0});
    v.push_back({P::kGovSpeedGain, 1.0});
    v.push_back({P::kLoadD, 1.0});
    return v;
  }();
  return o;
}

const std::vector<std::pair<std::string, const Overrides*>>& table() {
  static const std::vector<std::pair<std::string, const Overrides*>> t = {
      {"stornoway", &stornoway()}, {"stornoway_island", &stornoway_island()}};
  return t;
}

}  // namespace

std::vector<std::string> preset_names() {
  std::vector<std::string> names;
  for (const auto& [name, o] : table()) names.push_back(name);
  return names;
}

Params preset(const std::string& name) {
  for (const auto& [n, overrides] : table()) {
    if (n != name) continue;
    Params p;
    for (const auto& [id, value] : *overrides) p.set(id, value, "preset " + name);
    return p;
  }
  throw ConfigError(fmt::format("unknown preset '{}', expected one of: {}", name,
                                fmt::join(preset_names(), ", ")));
}

}  // namespace plantsim
