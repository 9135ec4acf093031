#include <algorithm>
#include <cmath>

#include "rig/diagnose/split.hpp"

namespace rig::diagnose {
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
  const int nw = 40;
  const Eigen::Index w = (n - start) / nw;
  ChangePoint cp;
  if (w < 16) return cp;
  std::vector<double> gain(nw);
  for (int i = 0; i < nw; ++i) {
    const Eigen::Index k = start + i * w;
    gain[static_cast<std::size_t>(i)] =
        (pr.y - base).segment(k, w).squaredNorm() - (pr.y - aug).segment(k, w).squaredNorm();
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
    if (std::abs(t) > std::max(4.0, best_t) && quiet < 0.25 * active) {
      best_t = std::abs(t);
      cp.found = true;
      cp.from = onset ? start + k * w : 0;
      cp.to = onset ? n : start + k * w;
    }
  }
  return cp;
}

}  // namespace

void refine_onsets(const Problem& pr, std::vector<HypothesisFit>& hs, const Eigen::VectorXd& base,
                   const FitOptions& fit) {
  if (pr.active_from > 0 || pr.active_to < pr.y.size()) return;  // already located in time
  int tried = 0;
  for (auto& h : hs) {
    if (tried >= 3) break;
    if (h.yhat.size() != pr.y.size() || h.score <= 0.0 ||
        kind_of(h.effects.front().effect) == EffectKind::kDisturbance)
      continue;
    ++tried;
    const ChangePoint cp = change_point(pr, base, h.yhat);
    if (!cp.found) continue;
    Problem gated = pr;
    gated.active_from = cp.from;
    gated.active_to = cp.to;
    HypothesisFit g = fit_hypothesis(gated, {h.effects}, base, fit);
    if (g.score > h.score) h = std::move(g);
  }
}

}  // namespace rig::diagnose
