// Pilot excitation analysis (DESIGN.md section 8, layer 1): a short low-amplitude run of the
// same excitation measures how much power deviation one % of bias produces,
//   g = sqrt(max(var(y) - s_n^2, 0)) / std(u)   (kW per %, s_n: steady-state noise std),
// and the main excitation's amplitude is planned by amplitude_plan.hpp so that the predicted
// peak stays inside plan_fraction of the band, capped so that the excitation's peak (its
// crest factor times its std) stays within the command clamp.
#pragma once

#include <string>
#include <vector>

namespace rig::session {

inline constexpr double kPeakFactor = 4.0;
inline constexpr double kExcitationClipSigma = 3.0;

struct PilotResult {
  double applied_std_pct = 0.0;  // std of the excitation as applied
  double response_std_kw = 0.0;  // excitation-driven part of the power deviation
  double gain_kw_per_pct = 0.0;
  double noise_std_kw = 0.0;
  double planned_std_pct = 0.0;    // main excitation std
  double predicted_peak_kw = 0.0;  // k_peak * g * s_u + 3 s_n
  double band_kw = 0.0;
  bool limited_by_clamp = false;
  bool ok = false;
  std::string reason;  // when !ok: why no amplitude could be planned
};

struct PilotPlanLimits {
  double band_kw = 0.0;
  double plan_fraction = 0.8;
  double clamp_pct = 5.0;
  double noise_std_kw = 0.0;
  // Peak / std of the excitation: 3 for the Gaussian (clipped at 3 sigma), 1 for the PRBS;
  // the planned std never lets the peak exceed the clamp.
  double input_crest = kExcitationClipSigma;
};

PilotResult analyse_pilot(const std::vector<double>& u_pct, const std::vector<double>& y_kw,
                          const PilotPlanLimits& limits);

}  // namespace rig::session
