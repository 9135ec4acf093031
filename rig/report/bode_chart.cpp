#include "rig/report/bode_chart.hpp"

#include <cmath>
#include <numbers>

namespace rig::report {
namespace {

// Phase in degrees, unwrapped so that consecutive points differ by less than 180 deg.
std::vector<double> unwrapped_phase_deg(const std::vector<std::complex<double>>& h) {
  std::vector<double> out;
  double offset = 0.0;
  double previous = 0.0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    double p = std::arg(h[i]) * 180.0 / std::numbers::pi;
    if (i > 0) {
      while (p + offset - previous > 180.0) offset -= 360.0;
      while (p + offset - previous < -180.0) offset += 360.0;
    }
    previous = p + offset;
    out.push_back(previous);
  }
  return out;
}

}  // namespace

std::vector<double> log_space(double f_lo_hz, double f_hi_hz, int n) {
  std::vector<double> out;
  const double a = std::log10(f_lo_hz), b = std::log10(f_hi_hz);
  for (int i = 0; i < n; ++i) {
    out.push_back(std::pow(10.0, n == 1 ? a : a + (b - a) * i / (n - 1)));
  }
  return out;
}

std::pair<Chart, Chart> bode_charts(const std::string& title, const std::vector<double>& freq_hz,
                                    const std::vector<BodeCurve>& curves) {
  Chart mag{title + ": magnitude", "frequency (Hz)", "|H|", freq_hz};
  mag.log_x = mag.log_y = true;
  Chart phase{title + ": phase", "frequency (Hz)", "phase (deg)", freq_hz};
  phase.log_x = true;
  for (const BodeCurve& c : curves) {
    Series m{c.label, {}, c.color};
    for (const auto& h : c.response) m.y.push_back(std::abs(h));
    m.points = c.points;
    if (c.points) m.width_px = 0;
    mag.series.push_back(m);
    Series p{c.label, unwrapped_phase_deg(c.response), c.color};
    p.points = c.points;
    if (c.points) p.width_px = 0;
    phase.series.push_back(p);
    if (c.phase_halfwidth_deg && c.phase_halfwidth_deg->size() == p.y.size()) {
      Series up{c.label + " upper", p.y, "rgba(31,119,180,0.5)", true};
      Series lo{c.label + " lower", p.y, "rgba(31,119,180,0.5)", true};
      for (std::size_t i = 0; i < p.y.size(); ++i) {
        up.y[i] += (*c.phase_halfwidth_deg)[i];
        lo.y[i] -= (*c.phase_halfwidth_deg)[i];
      }
      up.width_px = lo.width_px = 0.5;
      const std::size_t at = phase.series.size();
      phase.series.push_back(up);
      phase.series.push_back(lo);
      phase.bands.push_back({at, at + 1});
    }
    if (c.mag_lo && c.mag_hi) {
      const std::size_t hi = mag.series.size();
      mag.series.push_back({c.label + " upper", *c.mag_hi, "rgba(31,119,180,0.5)", true});
      mag.series.back().width_px = 0.5;
      mag.series.push_back({c.label + " lower", *c.mag_lo, "rgba(31,119,180,0.5)", true});
      mag.series.back().width_px = 0.5;
      mag.bands.push_back({hi, hi + 1});
    }
  }
  return {mag, phase};
}

}  // namespace rig::report
