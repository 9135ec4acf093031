#include "rig/diagnose/timing.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "rig/diagnose/augmented_model.hpp"

namespace rig::diagnose {
namespace {

// Golden-section steps: the interval shrinks to 0.618^12 = 0.3 % of a sample.
constexpr int kGoldenSteps = 12;

// The estimation samples' residual sum of squares with the dead time shifted by delta and an
// offset fitted.
double cost(const Problem& pr, double delta_s) {
  model::TransferFunction tf = pr.tf;
  tf.delay_s = std::max(0.0, tf.delay_s + delta_s);
  const Eigen::ArrayXd z = model::simulate(tf, pr.u, pr.dt_s).array();
  const Eigen::ArrayXd& w = pr.est_weight;
  const Eigen::ArrayXd r = pr.y.array() - z;
  const double offset = (w * r).sum() / std::max(w.sum(), 1.0);
  return (w * (r - offset).square()).sum();
}

}  // namespace

double absorb_timing_nuisance(Problem& pr) {
  if (pr.output_rc_s) return 0.0;  // the coupled output's offset is not constant: leave it
  const double lo = std::max(-0.5 * pr.dt_s, -pr.tf.delay_s), hi = 0.5 * pr.dt_s;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = lo, b = hi, c = b - g * (b - a), d = a + g * (b - a);
  double fc = cost(pr, c), fd = cost(pr, d);
  for (int i = 0; i < kGoldenSteps; ++i) {
    if (fc < fd) {
      b = d, d = c, fd = fc, c = b - g * (b - a), fc = cost(pr, c);
    } else {
      a = c, c = d, fc = fd, d = a + g * (b - a), fd = cost(pr, d);
    }
  }
  const double delta = 0.5 * (a + b);
  if (!(cost(pr, delta) < cost(pr, 0.0))) return 0.0;
  pr.tf.delay_s = std::max(0.0, pr.tf.delay_s + delta);
  finish_problem(pr);
  return delta;
}

}  // namespace rig::diagnose
