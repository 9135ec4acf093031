// After the excitation (run off the loop thread in real time): the final MMFM estimate with
// the sample-timing correction, H1, the applied level, the data-quality checks, and the rule
// that decides whether the data support a model (DESIGN.md section 8: a run whose data do
// not support a model writes none).
#pragma once

#include <string>
#include <vector>

#include "rig/session/online_mmfm.hpp"
#include "rig/session/session.hpp"

namespace rig::session {

struct ExcitationRecord {
  std::vector<double> u_pct;  // applied excitation
  std::vector<double> y_kw;   // P - P0
  double dt_s = 0.01;
  double timing_correction_s = 0.0;  // RunContext::timing_correction_s()
};

// The plant's dead time from one estimated on the rig's samples (never below 0): the one place
// the sample-timing correction meets a delay (RunContext::timing_correction_s).
double plant_delay_s(double estimated_delay_s, double timing_correction_s);

// Fills everything of `out` but planned_std_pct and stop_reason; delays and phases refer to
// the plant (the timing correction is applied once, at the end).
void analyse_excitation(OnlineMmfm& online, const ExcitationRecord& record, const TestConfig& c,
                        ExcitationResult& out);

// "" when the excitation supports a model, else why not (one line).
std::string why_no_model(const ExcitationResult& e, const TestConfig& c);

}  // namespace rig::session
