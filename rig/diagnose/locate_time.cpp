// Time location of the residual r = y - yhat.
//
// Time: windows of W samples; under stationarity ln(mean r^2) varies little between
// windows. A window is out of bounds when its ln mean square exceeds the quiet level (from
// the lower quartile) by more than 4.5 standard deviations and its rms by 15 %.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/residual_stats.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {
namespace {

// A residual that is loud where the input-driven signal is loud (a gain error in a record
// whose excitation level changes, as a commissioning test's phases do) is not located in
// time. The quiet windows give the residual's mean square as noise floor plus a share of
// the model output's, e_r = a + b e_z (least squares, a, b >= 0); a loud window stays
// located only when it exceeds that prediction by more than (1.5)^2.
void keep_unless_signal_proportional(const Eigen::VectorXd& z, Eigen::Index w,
                                     const std::vector<double>& lms, std::vector<bool>& loud) {
  const std::size_t m = lms.size();
  std::vector<double> ez(m), er(m);
  double sxx = 0, sx = 0, sy = 0, sxy = 0, k = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const Eigen::VectorXd zs = z.segment(static_cast<Eigen::Index>(i) * w, w);
    ez[i] = (zs.array() - zs.mean()).square().mean();
    er[i] = std::exp(lms[i]);
    if (loud[i]) continue;
    sxx += ez[i] * ez[i], sx += ez[i], sy += er[i], sxy += ez[i] * er[i], ++k;
  }
  const double det = k * sxx - sx * sx;
  if (k < 4 || det <= 1e-12 * k * sxx) return;  // the quiet windows do not span signal levels
  const double b = std::max(0.0, (k * sxy - sx * sy) / det);
  const double a = std::max(0.0, (sy - b * sx) / k);
  for (std::size_t i = 0; i < m; ++i)
    if (loud[i] && er[i] <= thresholds::kWindowOverSignalPrediction * (a + b * ez[i]))
      loud[i] = false;
}

}  // namespace

std::vector<TimeWindow> locate_time(const Problem& pr, const Eigen::VectorXd& r_all) {
  Eigen::Index start = 0;  // after the warm-up
  const Eigen::Index n = r_all.size();
  while (start < n && pr.est_weight(start) + pr.val_weight(start) <= 0.0) ++start;
  const Eigen::VectorXd r = r_all.tail(n - start);
  const Eigen::Index w = std::max<Eigen::Index>(64, r.size() / 40);
  std::vector<double> lms;
  for (Eigen::Index k = 0; k + w <= r.size(); k += w)
    lms.push_back(std::log(r.segment(k, w).squaredNorm() / static_cast<double>(w) + 1e-300));
  std::vector<TimeWindow> out;
  if (lms.size() < 4) return out;
  // Spread of ln(mean square) over W correlated samples: var = 2 c / W with
  // c = 1 + 2 sum rho_r(k)^2 (Bartlett), widened by half for the residual's non-Gaussianity.
  // c from the quiet windows (lower half), so a located effect does not widen its own bounds.
  const double q50 = quantile(lms, 0.5);
  double c_sum = 0.0;
  int quiet = 0;
  for (std::size_t i = 0; i < lms.size(); ++i)
    if (lms[i] <= q50) {
      const Eigen::VectorXd seg = r.segment(static_cast<Eigen::Index>(i) * w, w);
      c_sum += bartlett_factor(seg, seg, std::min<Eigen::Index>(200, w / 4)), ++quiet;
    }
  const double c = quiet > 0 ? c_sum / quiet : 1.0;
  const double s = 1.5 * std::sqrt(2.0 * c / static_cast<double>(w));
  // Reference: the lower quartile is 0.67 standard deviations below the quiet windows' mean.
  const double ref = quantile(lms, 0.25) + 0.67 * s;
  std::vector<bool> loud(lms.size());
  for (std::size_t i = 0; i < lms.size(); ++i) {
    const double excess = lms[i] - ref;
    loud[i] = excess > thresholds::kWindowExcessSds * s &&
              excess > 2.0 * std::log(thresholds::kWindowMinRmsRatio);
  }
  keep_unless_signal_proportional(pr.baseline_z.tail(n - start), w, lms, loud);
  for (std::size_t i = 0; i < lms.size(); ++i) {
    const double excess = lms[i] - ref;
    if (!loud[i]) continue;
    const double t0 = static_cast<double>(start + static_cast<Eigen::Index>(i) * w) * pr.dt_s;
    const double t1 = t0 + static_cast<double>(w) * pr.dt_s;
    const double ratio = std::exp(0.5 * excess);
    if (!out.empty() && std::abs(out.back().to_s - t0) < 1e-9) {
      out.back().to_s = t1;
      out.back().rms_ratio = std::max(out.back().rms_ratio, ratio);
    } else {
      out.push_back({t0, t1, ratio});
    }
  }
  return out;
}

}  // namespace rig::diagnose
