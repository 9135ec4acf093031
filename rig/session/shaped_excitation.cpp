#include "rig/session/shaped_excitation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "rig/ident/mmfm.hpp"
#include "rig/ident/output_error.hpp"
#include "rig/signal/ac_coupling.hpp"
#include "rig/signal/correlators.hpp"
#include "rig/signal/random.hpp"

namespace rig::session {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kCrestIterations = 200;
constexpr double kClipLevel = 0.85;  // clip at this share of the current peak
constexpr double kNoisePeakSigmas = 3.0;
constexpr Eigen::Index kPilotLags = 256;

model::TransferFunction pilot_model(const std::vector<double>& u_raw,
                                    const std::vector<double>& y_raw, const ShapedLimits& l) {
  const auto n = static_cast<Eigen::Index>(u_raw.size());
  Eigen::VectorXd u = Eigen::Map<const Eigen::VectorXd>(u_raw.data(), n);
  Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(y_raw.data(), n);
  if (l.ac_coupling_rc_s > 0.0) {
    u = signal::ac_couple(u, l.dt_s, l.ac_coupling_rc_s);
    y = signal::ac_couple(y, l.dt_s, l.ac_coupling_rc_s);
  }
  signal::CorrelatorOptions w;
  w.lags = kPilotLags;
  w.dt_s = l.dt_s;
  ident::MmfmOptions m;
  m.order = {2, 0};
  const model::TransferFunction start =
      ident::estimate_mmfm(signal::auto_correlation(u, w), signal::cross_correlation(y, u, w), m)
          .model;
  return ident::refine_output_error(u, y, l.dt_s, start, true).model;
}

struct Lines {
  std::vector<double> w_rad;            // per sample
  std::vector<double> out_amp, in_amp;  // output and input amplitudes at scale 1
  std::vector<double> gain_phase;       // arg G
};

Lines plan_lines(const model::TransferFunction& g, const ShapedLimits& l, ShapedDesign& d) {
  const double f0 = 1.0 / (kShapedPeriodSamples * l.dt_s);
  const int k_lo = std::max(1, static_cast<int>(std::ceil(l.f_lo_hz / f0)));
  const int k_hi =
      std::min(kShapedPeriodSamples / 2 - 1, static_cast<int>(std::floor(l.f_hi_hz / f0)));
  Lines s;
  std::vector<double> mags;
  for (int k = k_lo; k <= k_hi; ++k) {
    const std::complex<double> h = g.response(k * f0);
    s.w_rad.push_back(kTwoPi * k / kShapedPeriodSamples);
    s.in_amp.push_back(1.0 / std::abs(h));
    s.gain_phase.push_back(std::arg(h));
    mags.push_back(std::abs(h));
  }
  std::vector<double> sorted = s.in_amp;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const double cap = kMaxBoost * sorted[sorted.size() / 2];
  for (std::size_t i = 0; i < s.in_amp.size(); ++i) {
    s.in_amp[i] = std::min(s.in_amp[i], cap);
    s.out_amp.push_back(s.in_amp[i] * mags[i]);
  }
  d.lines = static_cast<int>(s.w_rad.size());
  d.f_lo_hz = k_lo * f0;
  d.f_hi_hz = k_hi * f0;
  return s;
}

Eigen::VectorXd synthesise(const std::vector<double>& amp, const std::vector<double>& w,
                           const std::vector<double>& phase) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kShapedPeriodSamples);
  for (std::size_t k = 0; k < amp.size(); ++k) {
    for (Eigen::Index t = 0; t < x.size(); ++t) {
      x(t) += amp[k] * std::cos(w[k] * static_cast<double>(t) + phase[k]);
    }
  }
  return x;
}

// Output phases of low crest factor: random start, then clip and re-project.
std::vector<double> low_crest_phases(const Lines& s, std::uint64_t seed) {
  signal::Xoshiro256 rng(seed);
  std::vector<double> phase(s.w_rad.size()), best;
  for (double& p : phase) p = kTwoPi * rng.uniform();
  double best_crest = 1e300;
  for (int it = 0; it < kCrestIterations; ++it) {
    Eigen::VectorXd y = synthesise(s.out_amp, s.w_rad, phase);
    const double peak = y.cwiseAbs().maxCoeff();
    const double crest = peak / std::sqrt(y.squaredNorm() / static_cast<double>(y.size()));
    if (crest < best_crest) best_crest = crest, best = phase;
    y = y.cwiseMax(-kClipLevel * peak).cwiseMin(kClipLevel * peak);
    for (std::size_t k = 0; k < phase.size(); ++k) {
      std::complex<double> c = 0.0;
      for (Eigen::Index t = 0; t < y.size(); ++t) {
        c += y(t) * std::polar(1.0, -s.w_rad[k] * static_cast<double>(t));
      }
      phase[k] = std::arg(c);
    }
  }
  return best;
}

double rms(const Eigen::VectorXd& x) {
  return std::sqrt(x.squaredNorm() / static_cast<double>(x.size()));
}

}  // namespace

Eigen::VectorXd repeat_period(const Eigen::VectorXd& period, Eigen::Index n) {
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) x(i) = period(i % period.size());
  return x;
}

ShapedDesign design_shaped_excitation(const std::vector<double>& pilot_u,
                                      const std::vector<double>& pilot_y, const ShapedLimits& l) {
  ShapedDesign d;
  d.dt_s = l.dt_s;
  try {
    d.pilot_model = pilot_model(pilot_u, pilot_y, l);
  } catch (const std::exception& e) {
    d.reason = std::string("no pilot model: ") + e.what();
    return d;
  }
  if (!d.pilot_model.is_stable()) {
    d.reason = "the pilot model is unstable";
    return d;
  }
  const Lines s = plan_lines(d.pilot_model, l, d);
  if (d.lines < 4) {
    d.reason = "fewer than 4 lines between f_lo and f_hi";
    return d;
  }
  const std::vector<double> out_phase = low_crest_phases(s, l.seed);
  std::vector<double> in_phase(out_phase.size());
  for (std::size_t k = 0; k < in_phase.size(); ++k) in_phase[k] = out_phase[k] - s.gain_phase[k];
  const Eigen::VectorXd y = synthesise(s.out_amp, s.w_rad, out_phase);
  const Eigen::VectorXd u = synthesise(s.in_amp, s.w_rad, in_phase);
  const double y_peak = y.cwiseAbs().maxCoeff(), u_peak = u.cwiseAbs().maxCoeff();
  d.output_crest = y_peak / rms(y);
  d.input_crest = u_peak / rms(u);
  const double room_kw = kOutputPeakFraction * l.band_kw - kNoisePeakSigmas * l.noise_std_kw;
  if (room_kw <= 0.0) {
    d.reason = fmt::format("noise {:.2f} kW std leaves no room in {:.0f} % of the {:.1f} kW band",
                           l.noise_std_kw, 100.0 * kOutputPeakFraction, l.band_kw);
    return d;
  }
  const double by_band = room_kw / (kShapedGainMargin * y_peak);
  const double by_clamp = kClampFraction * l.clamp_pct / u_peak;
  const double scale = std::min(by_band, by_clamp);
  d.limited_by_clamp = by_clamp < by_band;
  d.period_pct = scale * u;
  d.std_pct = scale * rms(u);
  d.predicted_peak_kw = kShapedGainMargin * scale * y_peak + kNoisePeakSigmas * l.noise_std_kw;
  d.ok = true;
  return d;
}

}  // namespace rig::session
