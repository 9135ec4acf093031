// Bode plots (magnitude and phase over log frequency) for reports, from model responses
// and measured FRFs, with an optional magnitude band (uncertainty interval).
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rig/report/html_report.hpp"

namespace rig::report {

struct BodeCurve {
  std::string label;
  std::vector<std::complex<double>> response;  // H(j 2 pi f) at the common frequencies
  std::optional<std::vector<double>> mag_lo;   // |H| bounds, drawn as a shaded band
  std::optional<std::vector<double>> mag_hi;
  bool points = false;  // measured FRF: markers, no line
  std::string color;
  std::optional<std::vector<double>> phase_halfwidth_deg;  // +- band around the phase
};

// Magnitude (log-log) and phase (deg, unwrapped along frequency) charts.
std::pair<Chart, Chart> bode_charts(const std::string& title, const std::vector<double>& freq_hz,
                                    const std::vector<BodeCurve>& curves);

// n frequencies spaced logarithmically from f_lo_hz to f_hi_hz (inclusive).
std::vector<double> log_space(double f_lo_hz, double f_hi_hz, int n);

}  // namespace rig::report
