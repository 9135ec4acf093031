#include <algorithm>
#include <cmath>

#include "rig/diagnose/screen.hpp"
#include "rig/diagnose/split.hpp"

namespace rig::diagnose {

using thresholds::kLevelShiftOfOutputStd;
using thresholds::kOnsetHypotheses;
using thresholds::kOnsetMinT;
using thresholds::kOnsetQuietFraction;
using thresholds::kOnsetWindows;

namespace {

struct ChangePoint {
  Eigen::Index from = 0, to = -1;  // active span in samples
  bool found = false;
};

ChangePoint change_point(const Problem& pr, const Eigen::VectorXd& base,
                         const Eigen::VectorXd& aug) {
  const Eigen::Index n = pr.y.size();
  Eigen::Index start = 0;
  while (start < n && pr.est_weight(start) + pr.val_weight(start) <= 0.0) ++start;
  const int nw = kOnsetWindows;
  const Eigen::Index w = (n - start) / nw;
  ChangePoint cp;
  if (w < 16) return cp;
  // The gain per window over the window's signal energy (the baseline output's mean square,
  // floored at a tenth of its median): an effect whose gain follows the excitation level
  // (a gain error in a record whose phases excite at different levels) has no onset.
  std::vector<double> gain(nw), energy(nw);
  for (int i = 0; i < nw; ++i) {
    const Eigen::VectorXd z = pr.baseline_z.segment(start + i * w, w);
    energy[static_cast<std::size_t>(i)] = (z.array() - z.mean()).square().mean();
  }
  std::vector<double> sorted = energy;
  std::nth_element(sorted.begin(), sorted.begin() + nw / 2, sorted.end());
  const double floor = std::max(0.1 * sorted[nw / 2], 1e-300);
  for (int i = 0; i < nw; ++i) {
    const Eigen::Index k = start + i * w;
    gain[static_cast<std::size_t>(i)] =
        ((pr.y - base).segment(k, w).squaredNorm() - (pr.y - aug).segment(k, w).squaredNorm()) /
        std::max(energy[static_cast<std::size_t>(i)], floor);
  }
  double best_t = 0.0;
  for (int k = 4; k <= nw - 4; ++k) {
    double m1 = 0, m2 = 0, v = 0;
    for (int i = 0; i < nw; ++i) (i < k ? m1 : m2) += gain[static_cast<std::size_t>(i)];
    m1 /= k, m2 /= nw - k;
    for (int i = 0; i < nw; ++i)
      v += std::pow(gain[static_cast<std::size_t>(i)] - (i < k ? m1 : m2), 2);
    const double se = std::sqrt(v / (nw - 2) * (1.0 / k + 1.0 / (nw - k)));
    const double t = se > 0 ? (m2 - m1) / se : 0.0;
    const bool onset = t > 0;
    const double active = onset ? m2 : m1, quiet = onset ? m1 : m2;
    if (std::abs(t) > std::max(kOnsetMinT, best_t) && quiet < kOnsetQuietFraction * active) {
      best_t = std::abs(t);
      cp.found = true;
      cp.from = onset ? start + k * w : 0;
      cp.to = onset ? n : start + k * w;
    }
  }
  return cp;
}

// h refitted on the change point's span when one was found, kept when its score rises.
void refit_from(const Problem& pr, const ChangePoint& cp, HypothesisFit& h,
                const Eigen::VectorXd& base, const FitOptions& fit) {
  if (!cp.found) return;
  Problem gated = pr;
  gated.active_from = cp.from;
  gated.active_to = cp.to;
  HypothesisFit g = fit_hypothesis(gated, {h.effects}, base, fit);
  if (g.score > h.score) h = std::move(g);
}

}  // namespace

Eigen::Index find_level_shift(const Problem& pr, const Eigen::VectorXd& r, double spreads) {
  const Eigen::Index n = r.size();
  const Eigen::Index w = std::max<Eigen::Index>(100, std::llround(2.0 / pr.dt_s));
  if (n < 8 * w) return -1;
  Eigen::VectorXd c(n + 1);  // prefix sums: mean(r[a, b)) = (c_b - c_a) / (b - a)
  c(0) = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) c(k + 1) = c(k) + r(k);
  const Eigen::Index m = n - 2 * w + 1;
  Eigen::VectorXd d(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Index k = i + w;
    d(i) = (c(k + w) - c(k)) / static_cast<double>(w) - (c(k) - c(k - w)) / static_cast<double>(w);
  }
  std::vector<double> v(d.data(), d.data() + m);
  const auto median = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2), x.end());
    return x[x.size() / 2];
  };
  const double med = median(v);
  for (double& x : v) x = std::abs(x - med);
  const double spread = 1.4826 * median(v);
  Eigen::Index best = 0;
  const double peak = (d.array() - med).abs().maxCoeff(&best);
  if (spread <= 0.0 || peak < spreads * spread || peak < kLevelShiftOfOutputStd * pr.scales.z_std)
    return -1;
  return best + w;
}

namespace {

// A level step (find_level_shift) is also when a measurement gain with the operating level
// in it changed: the gain change is fitted from the step on too, whatever it scored over
// the whole record (where the half without it dilutes it below its parameter's worth) or
// over the span the time windows located (droopsim seed 2 d017: with the grid's share taken
// out, a change point at 66 s located a gain change from 100 s, and the gain fitted from it
// read 0.948 against 0.907, 0.05 points over the fit from the step).
void refit_gain_from_step(const Problem& pr, std::vector<HypothesisFit>& hs,
                          const Eigen::VectorXd& base, const FitOptions& fit) {
  const Eigen::Index step_at = std::max(pr.level_shift_at, pr.level_step_removed_at);
  if (step_at <= 0) return;
  const auto gain = std::find_if(hs.begin(), hs.end(), [](const HypothesisFit& h) {
    return h.effects.size() == 1 && h.effects[0].effect == Effect::kGainChange;
  });
  if (gain == hs.end() || gain->yhat.size() != pr.y.size()) return;
  Problem gated = pr;
  gated.active_from = step_at;
  gated.active_to = pr.y.size();
  HypothesisFit g = fit_hypothesis(gated, {gain->effects}, base, fit);
  if (g.score >= gain->score - thresholds::kStepOnsetMarginPct) *gain = std::move(g);
}

}  // namespace

void refine_onsets(const Problem& pr, std::vector<HypothesisFit>& hs, const Eigen::VectorXd& base,
                   const FitOptions& fit) {
  if (pr.active_from > 0 || pr.active_to < pr.y.size()) {  // already located in time
    refit_gain_from_step(pr, hs, base, fit);
    return;
  }
  int tried = 0;
  for (auto& h : hs) {
    if (tried >= kOnsetHypotheses) break;
    // The curvature is static_nonlinearity's reduced form: the onset is searched on the full
    // forms, and an onset found re-searches every hypothesis on its span, the curvature too
    // (research_at_onset). Taking a place among the few, it pushed out the hypothesis whose
    // onset located a rack limit from 100 s (droopsim seed 4 d027).
    // A drift is a smooth of the residual, in-sample everywhere: it has no onset to find. A
    // periodic disturbance may start during the record (droopsim seed 8 d062, a ripple from
    // 100 s: over the whole record its line raised the fit by 0.7 points, less than its
    // parameters' penalty, and scored -0.11); what raises the fit at all is searched.
    if (h.yhat.size() != pr.y.size() || h.validation_fit_after <= h.validation_fit_before ||
        h.effects.front().effect == Effect::kDrift ||
        h.effects.front().effect == Effect::kCurvature)
      continue;
    ++tried;
    refit_from(pr, change_point(pr, base, h.yhat), h, base, fit);
  }
  refit_gain_from_step(pr, hs, base, fit);
}

void refine_onsets_beside(const Problem& pr, std::vector<HypothesisFit>& pairs,
                          const HypothesisFit& disturbance, const Eigen::VectorXd& base,
                          const FitOptions& fit) {
  if (pr.active_from > 0 || pr.active_to < pr.y.size() || disturbance.yhat.size() != pr.y.size())
    return;
  const int n = std::min<int>(kOnsetHypotheses, static_cast<int>(pairs.size()));
  for (int i = 0; i < n; ++i) {
    HypothesisFit& h = pairs[static_cast<std::size_t>(i)];
    if (h.yhat.size() != pr.y.size() || !(h.score > disturbance.score)) continue;
    refit_from(pr, change_point(pr, disturbance.yhat, h.yhat), h, base, fit);
  }
  rank(pairs);
}

}  // namespace rig::diagnose
