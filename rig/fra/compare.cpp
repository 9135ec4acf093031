#include "rig/fra/compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

namespace rig::fra {

const char* to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::kPass:
      return "pass";
    case Verdict::kFail:
      return "fail";
    case Verdict::kInsufficient:
      return "insufficient";
  }
  return "unknown";
}

namespace {

CompareRow compare_point(const ResponseFn& model, const model::FrfPoint& m,
                         const CompareTolerances& t) {
  CompareRow row;
  row.freq_hz = m.freq_hz;
  const std::complex<double> h = model(m.freq_hz);
  row.model_mag = std::abs(h);
  row.model_phase_deg = std::arg(h) * 180.0 / std::numbers::pi;
  row.mag_error_db = 20.0 * std::log10(m.mag / row.model_mag);
  row.phase_error_deg = model::wrap_deg(m.phase_deg - row.model_phase_deg);
  row.checked =
      m.freq_hz >= t.f_lo_hz && m.freq_hz <= t.f_hi_hz && m.valid && m.coherence >= t.min_coherence;
  // A NaN error (zero or non-finite magnitude) fails: the comparisons below are false.
  row.pass = row.checked && std::abs(row.mag_error_db) <= t.mag_db &&
             std::abs(row.phase_error_deg) <= t.phase_deg;
  return row;
}

}  // namespace

CompareResult compare(const ResponseFn& model, const std::vector<model::FrfPoint>& measured,
                      const CompareTolerances& t) {
  if (!model) throw std::invalid_argument("compare: a model response is required");
  if (!(t.mag_db > 0.0) || !(t.phase_deg > 0.0)) {
    throw std::invalid_argument("compare: tolerances mag_db and phase_deg must be > 0");
  }
  CompareResult r;
  for (const model::FrfPoint& m : measured) {
    CompareRow row = compare_point(model, m, t);
    if (row.checked) {
      ++r.checked;
      if (!row.pass) ++r.failed;
      r.max_abs_mag_error_db = std::max(r.max_abs_mag_error_db, std::abs(row.mag_error_db));
      r.max_abs_phase_error_deg =
          std::max(r.max_abs_phase_error_deg, std::abs(row.phase_error_deg));
      if (std::isnan(row.mag_error_db)) r.max_abs_mag_error_db = row.mag_error_db;
    }
    r.rows.push_back(row);
  }
  if (r.failed > 0) {
    r.verdict = Verdict::kFail;
  } else if (r.checked >= t.min_points) {
    r.verdict = Verdict::kPass;
  }
  char line[256];
  std::snprintf(line, sizeof line,
                "%s: %d of %d points checked in %.2f-%.2f Hz, %d outside +-%.2f dB / +-%.1f deg; "
                "max error %.2f dB, %.1f deg",
                to_string(r.verdict), r.checked, static_cast<int>(measured.size()), t.f_lo_hz,
                t.f_hi_hz, r.failed, t.mag_db, t.phase_deg, r.max_abs_mag_error_db,
                r.max_abs_phase_error_deg);
  r.summary = line;
  return r;
}

}  // namespace rig::fra
