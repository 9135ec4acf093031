// Disturbance tests and the whole location step.
//
// Periodic: a residual spectral line, PSD over the median of its neighbours (+-8 bins
// without +-1) above 12, at a bin where the residual is not coherent with the input. For M
// averaged segments the ratio of white noise is about chi^2(2M)/2M, so 12 is far beyond
// chance; the line's frequency is then refined by maximising |sum r_t e^{-j w t}| on a fine
// grid (+-1.5 bins).
// Drift: the residual smoothed over tau_d = max(50 dt, T/40) carries more than 10 % of its
// variance and 30 times what white noise would leave (dt / tau_d), and is not the smoothed
// model output's shadow (|corr| < 0.7; a missing low-frequency dynamic would be near 1,
// while two independent slow records of T/tau_d effective samples correlate by chance).
#include "rig/diagnose/locate.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {
namespace {

double line_power(const Problem& pr, const Eigen::VectorXd& r, double f) {
  std::complex<double> acc = 0.0;
  const double w = 2.0 * std::numbers::pi * f * pr.dt_s;
  for (Eigen::Index k = 0; k < r.size(); ++k)
    if (pr.est_weight(k) > 0.0) acc += r(k) * std::polar(1.0, -w * static_cast<double>(k));
  return std::norm(acc);
}

void find_line(const Problem& pr, const Eigen::VectorXd& r, const FrequencyLocation& fl,
               Disturbances& d) {
  const auto& b = fl.bins;
  const int nb = static_cast<int>(b.size());
  for (int k = 2; k + 2 < nb; ++k) {
    if (b[static_cast<std::size_t>(k)].significant) continue;
    std::vector<double> nbr;
    for (int j = std::max(0, k - 8); j <= std::min(nb - 1, k + 8); ++j)
      if (std::abs(j - k) > 1) nbr.push_back(b[static_cast<std::size_t>(j)].residual_psd);
    std::nth_element(nbr.begin(), nbr.begin() + static_cast<long>(nbr.size() / 2), nbr.end());
    const double ratio =
        b[static_cast<std::size_t>(k)].residual_psd / std::max(nbr[nbr.size() / 2], 1e-300);
    if (ratio > d.line_ratio)
      d.line_ratio = ratio, d.line_freq_hz = b[static_cast<std::size_t>(k)].freq_hz;
  }
  d.periodic = d.line_ratio > thresholds::kLineToNeighbours;
  if (!d.periodic || nb < 2) return;
  const double df = b[1].freq_hz - b[0].freq_hz;
  double best = -1.0, f0 = d.line_freq_hz;
  for (int i = -30; i <= 30; ++i) {
    const double f = f0 + 1.5 * df * i / 30.0;
    const double p = line_power(pr, r, f);
    if (p > best) best = p, d.line_freq_hz = f;
  }
}

double corr(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd x = a.array() - a.mean(), y = b.array() - b.mean();
  const double d = std::sqrt(x.squaredNorm() * y.squaredNorm());
  return d > 0.0 ? x.dot(y) / d : 0.0;
}

}  // namespace

double drift_smooth_s(const Problem& pr) {
  return std::max(thresholds::kDriftSmoothMinSamples * pr.dt_s,
                  pr.scales.duration_s / thresholds::kDriftSmoothRecordDivisor);
}

Disturbances locate_disturbances(const Problem& pr, const Eigen::VectorXd& r,
                                 const FrequencyLocation& fl) {
  Disturbances d;
  find_line(pr, r, fl, d);
  Eigen::Index from = 0;
  while (from < r.size() && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::VectorXd rs = r.tail(r.size() - from);
  d.drift_tau_s = drift_smooth_s(pr);
  const Eigen::VectorXd s = smooth_zero_phase(rs, d.drift_tau_s, pr.dt_s);
  const double vr = (rs.array() - rs.mean()).square().mean();
  const double vs = (s.array() - s.mean()).square().mean();
  d.drift_ratio = vr > 0.0 ? vs / vr : 0.0;
  const Eigen::VectorXd zs =
      smooth_zero_phase(pr.baseline_z.tail(r.size() - from), d.drift_tau_s, pr.dt_s);
  d.drift = d.drift_ratio > thresholds::kDriftShare &&
            d.drift_ratio > thresholds::kDriftOverWhite * pr.dt_s / d.drift_tau_s &&
            std::abs(corr(s, zs)) < thresholds::kDriftNotModelCorr;
  return d;
}

namespace {

bool input_tests_fail(const Location& loc) {
  return loc.freq.band_hz.has_value() || !loc.tests.independent || loc.half_dependent >= 0 ||
         loc.amp.fails();
}

// The cross-correlation test on each half of r (after the warm-up), the 1 % shared.
void test_halves(const Problem& pr, const Eigen::VectorXd& r, Eigen::Index from, Eigen::Index lags,
                 Location& loc) {
  const Eigen::Index n = r.size() - from, half = n / 2;
  if (half < 4 * lags) return;
  for (int i = 0; i < 2; ++i) {
    const Eigen::Index at = from + i * half, len = i == 0 ? half : n - half;
    loc.halves[static_cast<std::size_t>(i)] =
        residual_tests(r.segment(at, len), pr.u.segment(at, len), pr.dt_s, lags, 2.0);
    if (!loc.halves[static_cast<std::size_t>(i)].independent && loc.half_dependent < 0)
      loc.half_dependent = i;
  }
}

// The input tests again on the residual with the drift taken out: a wander of the output
// inflates the residual's low-frequency power and its autocorrelation, which widen every
// test's bound, and can hide an input-side effect behind it (a rack limit behind the grid's
// wander). The drift is the residual's zero-phase smooth at the drift test's time scale,
// slow against the excitation, so it takes little of an input-driven part.
void look_behind_drift(const Problem& pr, const Eigen::VectorXd& r, const Eigen::VectorXd& yhat,
                       Eigen::Index lags, Location& loc) {
  const Eigen::VectorXd rc = r - smooth_zero_phase(r, loc.dist.drift_tau_s, pr.dt_s);
  Location behind = loc;
  behind.freq = locate_frequency(pr, rc);
  behind.amp = locate_amplitude(pr, rc, yhat);
  Eigen::Index from = 0;
  while (from < r.size() && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  behind.tests =
      residual_tests(rc.tail(rc.size() - from), pr.u.tail(rc.size() - from), pr.dt_s, lags);
  behind.halves = {};
  behind.half_dependent = -1;
  test_halves(pr, rc, from, lags, behind);
  if (!input_tests_fail(behind)) return;
  behind.input_mismatch = true;
  behind.behind_drift = true;
  loc = std::move(behind);
}

}  // namespace

Eigen::Index residual_test_lags(const Problem& pr, const Location& loc) {
  const double band = std::max(loc.freq.input_band_hz, 1.0 / pr.scales.duration_s);
  return std::clamp<Eigen::Index>(std::llround(2.0 / (band * pr.dt_s)), 25, 200);
}

Location locate(const Problem& pr, const Eigen::VectorXd& yhat) {
  Location loc;
  const Eigen::VectorXd r = pr.y - yhat;
  loc.freq = locate_frequency(pr, r);
  loc.windows = locate_time(pr, r);
  loc.amp = locate_amplitude(pr, r, yhat);
  Eigen::Index from = 0;
  while (from < r.size() && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::Index lags = residual_test_lags(pr, loc);
  loc.tests = residual_tests(r.tail(r.size() - from), pr.u.tail(r.size() - from), pr.dt_s, lags);
  test_halves(pr, r, from, lags, loc);
  loc.dist = locate_disturbances(pr, r, loc.freq);
  loc.clip = pr.output_clip;
  loc.input_mismatch = input_tests_fail(loc);
  loc.disturbance = loc.dist.periodic || loc.dist.drift;
  if (loc.dist.drift && !loc.input_mismatch) look_behind_drift(pr, r, yhat, lags, loc);
  return loc;
}

}  // namespace rig::diagnose
