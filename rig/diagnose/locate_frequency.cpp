// Frequency location: H1 of the recording against the model, and the residual's coherence
// with the input. Under "the residual is noise independent of u", the magnitude-squared
// coherence estimated from M independent segments exceeds c with probability
// (1 - c)^{M-1}; bins above c = 1 - alpha^{1/(M_eff - 1)} (alpha shared over the bins
// tested, Bonferroni; M_eff = 0.75 M for Hann windows overlapping by half) are where the
// model's response differs from the recording's beyond its uncertainty.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "rig/diagnose/locate.hpp"
#include "rig/fra/h1.hpp"

namespace rig::diagnose {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::complex<double> model_response(const Problem& pr, double f) {
  std::complex<double> g = pr.tf.response(f);
  if (pr.output_rc_s) {
    const std::complex<double> s(0.0, kTwoPi * f * *pr.output_rc_s);
    g *= s / (1.0 + s);
  }
  return g;
}

// Seeds for dead time, lag, gain and resonance from e = H1/G over coherent bins.
void phase_and_gain_seeds(FrequencyLocation& loc) {
  double swf2 = 0.0, swfp = 0.0, sw = 0.0, swg = 0.0, swt = 0.0, swl = 0.0, prev = 0.0;
  bool first = true;
  for (const auto& b : loc.bins) {
    if (b.coherence < 0.5 || b.freq_hz > loc.input_band_hz) continue;
    const std::complex<double> e = b.measured / b.model;
    double ph = std::arg(e);
    if (!first) ph = prev + std::remainder(ph - prev, kTwoPi);
    prev = ph, first = false;
    const double w = b.coherence / std::max(1e-3, 1.0 - b.coherence);
    swf2 += w * b.freq_hz * b.freq_hz;
    swfp += w * b.freq_hz * ph;
    sw += w;
    swg += w * std::abs(e);
    if (ph < -0.05 && ph > -1.4) swt += w * std::tan(-ph) / (kTwoPi * b.freq_hz), swl += w;
    const double dev = std::abs(std::log(std::abs(e)));
    if (dev > std::abs(std::log(loc.peak_ratio))) {
      loc.peak_ratio = std::abs(e);
      loc.peak_ratio_freq_hz = b.freq_hz;
    }
  }
  if (swf2 > 0.0) loc.delay_from_phase_s = -swfp / (kTwoPi * swf2);
  if (sw > 0.0) loc.gain_ratio = swg / sw;
  if (swl > 0.0) loc.lag_from_phase_s = swt / swl;
}

}  // namespace

Eigen::Index welch_segment(Eigen::Index n) {
  Eigen::Index l = 64;
  while (l * 2 <= n / 8 && l < 4096) l *= 2;
  return l;
}

FrequencyLocation locate_frequency(const Problem& pr, const Eigen::VectorXd& r,
                                   Eigen::Index segment_length) {
  fra::WelchOptions wo;
  wo.segment_length = segment_length > 0 ? segment_length : welch_segment(pr.u.size());
  const fra::CrossSpectra sy = fra::welch_cross_spectra(pr.u, pr.y, pr.dt_s, wo);
  const fra::CrossSpectra sr = fra::welch_cross_spectra(pr.u, r, pr.dt_s, wo);
  FrequencyLocation loc;
  loc.segments = sy.segments;
  const double guu_max = sy.guu.tail(sy.guu.size() - 1).maxCoeff();
  // Scale of a one-sided PSD per Hz for a Hann window: 2 dt / (L sum w^2 / L) / M.
  const double l = static_cast<double>(wo.segment_length);
  const double psd_scale = 2.0 * pr.dt_s / (0.375 * l) / std::max(1, sr.segments);
  int tested = 0;
  for (Eigen::Index k = 1; k < sy.freq_hz.size(); ++k) {
    if (sy.guu(k) >= 0.01 * guu_max) loc.input_band_hz = sy.freq_hz(k), ++tested;
  }
  const double m_eff = std::max(2.0, 0.75 * sy.segments);
  const double alpha = 0.01 / std::max(1, tested);
  loc.coherence_threshold = 1.0 - std::pow(alpha, 1.0 / (m_eff - 1.0));
  for (Eigen::Index k = 1; k < sy.freq_hz.size(); ++k) {
    FrequencyBin b;
    b.freq_hz = sy.freq_hz(k);
    b.model = model_response(pr, b.freq_hz);
    b.measured = sy.guu(k) > 0.0 ? sy.gyu(k) / sy.guu(k) : 0.0;
    b.coherence =
        sy.guu(k) * sy.gyy(k) > 0.0 ? std::norm(sy.gyu(k)) / (sy.guu(k) * sy.gyy(k)) : 0.0;
    b.residual_coherence =
        sr.guu(k) * sr.gyy(k) > 0.0 ? std::norm(sr.gyu(k)) / (sr.guu(k) * sr.gyy(k)) : 0.0;
    b.residual_psd = sr.gyy(k) * psd_scale;
    if (sr.guu(k) > 0.0) b.residual_response = sr.gyu(k) / sr.guu(k);
    b.significant = sy.guu(k) >= 0.01 * guu_max && b.residual_coherence > loc.coherence_threshold;
    if (b.significant) {
      if (!loc.band_hz) loc.band_hz = std::make_pair(b.freq_hz, b.freq_hz);
      loc.band_hz->second = b.freq_hz;
    }
    loc.bins.push_back(b);
  }
  phase_and_gain_seeds(loc);
  return loc;
}

}  // namespace rig::diagnose
