// Concealed-effect recordings made by the emulated plant (plantsim, CVODE): the proof data
// of `rig diagnose` (issue: "the proof on concealed data").
//
// The nominal model is the Stornoway preset's linearised transfer function (the same as
// plantsim/presets/stornoway.tf.json) plus half a sample of dead time for the zero-order hold
// of the recorded setpoint. The recording is the preset excited by a +-3 % power Gaussian bias
// (0.8 % rms, 4 Hz band, clipped at 3 sigma) at 100 Hz, with the preset's own noise, drift,
// mains pick-up and firing ripple, and ONE plant parameter changed that the model does not
// know (plant_effects()). The effect is concealed one of four ways:
//   noise        transducer noise raised from 5 to 15 kW rms (effect small against it)
//   drift        a 20 kW rms slow drift (Ornstein-Uhlenbeck, 60 s) added to the power
//   ac_coupling  the power signal AC-coupled (RC 5 s) and the sidecar saying so
//   partial      the effect appears half-way through the record only
// The truth is expressed in the units of the diagnosed effect's first parameter
// (its parameter_specs in rig/diagnose/effects/<effect>.cpp), converted from the plant parameter by
// the plant's own scales (governor droop, rack position per % bias from the linearisation).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose::bench {

struct PlantEffect {
  std::string effect;       // DESIGN.md 9 word, or "none"
  std::string plant_key;    // the plantsim parameter changed (empty for none)
  double plant_value = 0;   // its concealed value
  std::string description;  // what happened to the set, in words
};

// The effects plantsim can hide (12, each a plant parameter) and the null case first.
const std::vector<PlantEffect>& plant_effects();
const std::vector<std::string>& concealments();  // noise, drift, ac_coupling, partial

// The concealments that make sense for an effect: a null case is not concealed by drift
// (added drift is an effect), a coupling does not switch on mid-record nor hide behind a
// declared coupling, a disturbance does not hide behind another disturbance, and a declared
// coupling would remove most of a slow drift.
std::vector<std::string> concealments_for(const std::string& effect);

// The plant (Stornoway preset, 10 ms tick, the preset's own disturbances, `faults` as
// plantsim --fault strings) driven by the +-3 % power Gaussian bias of every plant case
// (0.8 % rms, 4 Hz band, clipped at 3 sigma, drawn with `excitation_seed`) at 100 Hz after
// settle_s at the operating point: u, and y in kW measured before each u is applied.
struct PlantRecord {
  Eigen::VectorXd u, y;
};
PlantRecord record_plant(const std::vector<std::string>& faults, std::uint64_t plant_seed,
                         std::uint64_t excitation_seed, double duration_s, double settle_s);

struct PlantCaseSpec {
  std::string effect = "none";
  std::string concealment = "noise";
  std::uint64_t seed = 1;
  double duration_s = 300.0;
};

struct PlantCase {
  DiagnoseInput input;
  double truth = 0.0;  // the effect's first parameter in diagnose units (NaN: not compared)
  std::string param;   // its name
  std::vector<std::string> faults;  // the plantsim --fault strings used
  std::string description;
};

// Throws std::invalid_argument for an unknown effect or concealment.
PlantCase make_plant_case(const PlantCaseSpec& spec);

// The verdicts counted as correct for a true effect: the effect itself, and for a lag also
// the other lag (extra_lag and sensor_lag are the same input-output dynamics when the
// measurement disturbances enter after both).
bool verdict_matches(const std::string& truth, const std::string& verdict);

}  // namespace rig::diagnose::bench
