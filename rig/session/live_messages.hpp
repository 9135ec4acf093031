// The bodies of the live feed's estimate, bode and sweep_point messages (docs/live.md), built
// from the session's own types. Phases publish them through TickLoop::live().
#pragma once

#include <nlohmann/json.hpp>

#include "rig/fra/stepped_sine.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/session/online_mmfm.hpp"

namespace rig::session {

// One block estimate: parameters with standard errors, derived gain/fn/zeta, the plant's
// dead time (the pair timing corrected) and the 95 % band of the model.
nlohmann::json estimate_message(const BlockEstimate& e, double timing_correction_s);
// The model's response over [from_hz, to_hz] (log spaced), magnitude in dB of kW per % and
// phase in degrees unwrapped, the pair timing corrected.
nlohmann::json bode_message(const model::TransferFunction& model, double from_hz, double to_hz,
                            double timing_correction_s, double t_s);
// One swept-sine point, the pair timing corrected like the model.
nlohmann::json sweep_point_message(const fra::SteppedSineResult& r, double timing_correction_s,
                                   double t_s);

}  // namespace rig::session
