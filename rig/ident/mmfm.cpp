// MMFM with automatic time scale and dead time (thesis 5-1-1 and 5-1-2: accuracy depends
// on the function scale and placement; a residual delay biases every parameter).
#include "rig/ident/mmfm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rig::ident {
namespace {

constexpr double kGolden = 0.6180339887498949;

// Score of one configuration: correlation-domain output error fit (higher is better).
double score_of(const MmfmResult& r) {
  const double f = r.correlation_fit_pct;
  return std::isfinite(f) && r.model.is_stable() ? f : -1e300;
}

struct Evaluator {
  const signal::Correlation& ruu;
  const signal::Correlation& ryu;
  model::ModelOrder order;
  MmfmSettings settings;
  int evaluations = 0;

  MmfmResult at(double delay_s) {
    ++evaluations;
    return mmfm_solve(ruu, ryu, order, delay_s, settings);
  }
};

// Lag (>= 0) where |r_yu| first reaches half its peak over positive lags: the dead time lies
// below it (the correlation's rise is smeared earlier by the width of r_uu, never later).
double half_rise_lag_s(const signal::Correlation& ryu) {
  const Eigen::Index z = ryu.zero_index;
  const double peak = ryu.r.tail(ryu.size() - z).cwiseAbs().maxCoeff();
  for (Eigen::Index i = z; i < ryu.size(); ++i)
    if (std::abs(ryu.r(i)) >= 0.5 * peak) return ryu.lag_s(i);
  return 0.0;
}

// Dominant time scale of r_yu: the lag span holding the middle 80 % of sum |r_yu| over
// positive lags (a resonance's ringing or a lag's decay).
double dominant_time_scale_s(const signal::Correlation& ryu) {
  const Eigen::Index z = ryu.zero_index;
  const Eigen::VectorXd a = ryu.r.tail(ryu.size() - z).cwiseAbs();
  const double total = a.sum();
  double acc = 0.0, t10 = 0.0, t90 = 0.0;
  bool got10 = false;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    acc += a(i);
    if (!got10 && acc >= 0.1 * total) t10 = static_cast<double>(i) * ryu.dt_s, got10 = true;
    if (acc >= 0.9 * total) {
      t90 = static_cast<double>(i) * ryu.dt_s;
      break;
    }
  }
  return std::max(t90 - t10, 4.0 * ryu.dt_s);
}

// Grid then golden-section search of the delay maximising the score.
MmfmResult search_delay(Evaluator& ev, double lo, double hi, double resolution_s) {
  const int grid = std::max(2, std::min(24, static_cast<int>((hi - lo) / resolution_s) + 1));
  MmfmResult best;
  double best_score = -std::numeric_limits<double>::infinity();
  int best_i = 0;
  for (int i = 0; i < grid; ++i) {
    const double td = grid == 1 ? lo : lo + (hi - lo) * i / (grid - 1.0);
    MmfmResult r = ev.at(td);
    if (score_of(r) > best_score) best_score = score_of(r), best = r, best_i = i;
  }
  if (hi <= lo) return best;
  const double step = (hi - lo) / (grid - 1.0);
  double a = std::max(lo, lo + (best_i - 1) * step), b = std::min(hi, lo + (best_i + 1) * step);
  double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
  MmfmResult r1 = ev.at(x1), r2 = ev.at(x2);
  while (b - a > resolution_s / 50.0) {
    if (score_of(r1) >= score_of(r2)) {
      b = x2, x2 = x1, r2 = r1, x1 = b - kGolden * (b - a), r1 = ev.at(x1);
    } else {
      a = x1, x1 = x2, r1 = r2, x2 = a + kGolden * (b - a), r2 = ev.at(x2);
    }
  }
  for (const MmfmResult* r : {&r1, &r2})
    if (score_of(*r) > best_score) best_score = score_of(*r), best = *r;
  return best;
}

// Delay standard error from the curvature of V(Td) = |r_yu - r_yu_hat(Td)|^2:
// var(Td) ~ 2 s^2 / V'', s^2 = V / (L - p - 1) (correlation errors treated as white).
double delay_std_from_curvature(Evaluator& ev, const MmfmResult& best) {
  const double h = 0.25 * ev.ryu.dt_s;
  auto v_at = [&](double td) {
    const MmfmResult r = ev.at(std::max(0.0, td));
    return (ev.ryu.r - r.model_ryu.r).squaredNorm();
  };  // model_ryu includes the fitted initial transient
  const double v0 = (ev.ryu.r - best.model_ryu.r).squaredNorm();
  const double td = std::max(best.delay_s, h);
  const double vpp = (v_at(td + h) - 2.0 * v_at(td) + v_at(td - h)) / (h * h);
  const double dof = static_cast<double>(ev.ryu.size() - (ev.order.n + ev.order.m + 2));
  if (!(vpp > 0.0) || dof <= 0.0) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(2.0 * (v0 / dof) / vpp);
}

}  // namespace

MmfmResult estimate_mmfm(const signal::Correlation& ruu, const signal::Correlation& ryu,
                         const MmfmOptions& options) {
  if (ryu.size() < 8 || ruu.size() != ryu.size())
    throw std::invalid_argument("estimate_mmfm: correlations need >= 8 lags on one lag axis");
  const double dt = ryu.dt_s;
  double td_lo = 0.0, td_hi = 0.0;
  if (options.delay_s) {
    td_lo = td_hi = *options.delay_s;
  } else {
    td_hi = options.max_delay_s >= 0.0 ? options.max_delay_s : half_rise_lag_s(ryu);
  }
  MmfmSettings base;
  base.family = options.family;
  base.functions = options.functions;
  base.solver = options.solver;
  base.normalisation = options.normalisation;
  // Candidate scales: the largest that fits, and multiples of the dominant time scale.
  std::vector<double> scales;
  if (options.scale_s) {
    scales.push_back(*options.scale_s);
  } else {
    base.scale_s = 1.0;
    const double unit_hw = support_half_width_s(options.order, base);
    const double span = (ryu.lag_s(ryu.size() - 1) - ryu.lag_s(0)) - td_hi;
    const double s_max = 0.5 * span / unit_hw;
    const double s_dom = dominant_time_scale_s(ryu) / unit_hw;
    for (double f : {0.1, 0.2, 0.35, 0.5, 0.7, 1.0, 1.4, 2.0})
      if (f * s_dom <= s_max && f * s_dom >= 2.0 * dt) scales.push_back(f * s_dom);
    scales.push_back(s_max);
  }
  MmfmResult best;
  double best_score = -std::numeric_limits<double>::infinity();
  for (double s : scales) {
    MmfmSettings st = base;
    st.scale_s = s;
    st.centres_s = admissible_centres(ruu, ryu, options.order, td_lo, td_hi, st, options.centres);
    if (st.centres_s.empty()) continue;
    for (int level = 1; level < options.scale_levels; ++level) {
      MmfmSettings wide = st;
      wide.scale_s = s * std::pow(3.0, level);
      MmfmBand band{wide.scale_s, admissible_centres(ruu, ryu, options.order, td_lo, td_hi, wide,
                                                     options.centres)};
      if (band.centres_s.empty()) break;
      st.extra_bands.push_back(std::move(band));
    }
    Evaluator ev{ruu, ryu, options.order, st};
    MmfmResult r = search_delay(ev, td_lo, td_hi, dt);
    if (score_of(r) > best_score || best.equations == 0) best_score = score_of(r), best = r;
  }
  if (best.equations == 0)
    throw std::invalid_argument(
        "estimate_mmfm: no modulating-function scale fits the correlation window");
  if (!options.delay_s) {
    Evaluator ev{ruu, ryu, options.order, best.settings};
    best.delay_std_s = delay_std_from_curvature(ev, best);
  }
  best.parameters = parameter_table(best.model, best.covariance, best.delay_std_s);
  if (options.refine) return refine_correlation_output_error(ruu, ryu, best, !options.delay_s);
  return best;
}

}  // namespace rig::ident
