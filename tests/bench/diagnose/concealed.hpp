// Recordings with one effect present that the nominal model lacks, concealed: small against
// the noise at a +-3 % power excitation, masked by drift or by a declared AC coupling, or
// present in part of the record only. The proof data of `rig diagnose` (tests, benchmark,
// the `diagnose_conceal` example program): test data, kept out of the product library.
//
// The "true" plant is simulated five times finer than the recording (input interpolated
// linearly, output decimated), so the diagnosis never sees its own discretisation.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {

enum class Concealment { kNoise, kDrift, kAcCoupling, kPartial };
const char* to_string(Concealment c);

struct ConcealedSpec {
  std::optional<Effect> effect;  // nullopt: the null case (the nominal model is right)
  Concealment concealment = Concealment::kNoise;
  std::uint64_t seed = 1;
  double duration_s = 300.0;
  double dt_s = 0.01;
  double noise_to_signal = 0.3;  // white noise std over the clean output's std
};

struct ConcealedRecording {
  DiagnoseInput input;        // nominal model, recorded u and y (with offsets)
  std::vector<double> truth;  // the effect's parameters as parameter_specs() names them
  std::string primary_param;  // the parameter the benchmark checks (truth[0])
  std::string description;
};

// The nominal model: a 46 kW/% set with its electromechanical mode at 2 Hz, damping 0.1,
// a 60 ms dead time and a 30 ms combustion lag (the Stornoway SOPDT of DESIGN.md 7).
model::TransferFunction nominal_genset_model();

// The effect's true parameters used by make_concealed (in parameter_specs() units), for
// the input and model scales of the spec.
ConcealedRecording make_concealed(const ConcealedSpec& spec);

}  // namespace rig::diagnose
