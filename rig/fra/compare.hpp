// Model versus measured frequency response (the `rig compare` check and the commissioning
// acceptance of the MMFM model against the swept sine).
//
// Per point: mag_error_db = 20 log10(|H_meas| / |H_model|),
//            phase_error_deg = wrap(arg H_meas - arg H_model) in (-180, 180],
// so a delay or sign convention off by whole turns does not count. A point is checked when
// it lies in [f_lo_hz, f_hi_hz], the estimator marked it valid and its coherence reaches
// min_coherence; it passes when both errors are within tolerance. The verdict is kPass when
// at least min_points are checked and all of them pass, kFail when any checked point fails,
// kInsufficient when too few points are good enough to judge.
#pragma once

#include <string>
#include <vector>

#include "rig/fra/frf.hpp"

namespace rig::fra {

struct CompareTolerances {
  double mag_db = 1.0;
  double phase_deg = 5.0;
  double f_lo_hz = 0.5;
  double f_hi_hz = 5.0;
  double min_coherence = 0.8;
  int min_points = 3;
};

struct CompareRow {
  double freq_hz = 0.0;
  double model_mag = 0.0;
  double model_phase_deg = 0.0;
  double mag_error_db = 0.0;
  double phase_error_deg = 0.0;
  bool checked = false;  // in band and of good quality
  bool pass = false;     // checked and within both tolerances
};

enum class Verdict { kPass, kFail, kInsufficient };
const char* to_string(Verdict verdict);

struct CompareResult {
  std::vector<CompareRow> rows;
  int checked = 0;
  int failed = 0;
  double max_abs_mag_error_db = 0.0;     // over checked points
  double max_abs_phase_error_deg = 0.0;  // over checked points
  Verdict verdict = Verdict::kInsufficient;
  std::string summary;  // one line for the human report
};

// Throws std::invalid_argument for an empty model or non-positive tolerances.
CompareResult compare(const ResponseFn& model, const std::vector<model::FrfPoint>& measured,
                      const CompareTolerances& tolerances = {});

// Any model with `response(freq_hz)`, e.g. rig::model::TransferFunction.
template <HasResponse Model>
CompareResult compare(const Model& model, const std::vector<model::FrfPoint>& measured,
                      const CompareTolerances& tolerances = {}) {
  return compare(as_response_fn(model), measured, tolerances);
}

}  // namespace rig::fra
