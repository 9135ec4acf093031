// Time and amplitude location of the residual r = y - yhat.
//
// Time: windows of W samples; under stationarity ln(mean r^2) varies little between
// windows. A window is out of bounds when its ln mean square exceeds the quiet level (from
// the lower quartile) by more than 4.5 standard deviations and its rms by 15 %.
//
// Amplitude: the input is split by level |u| into five quantile bands u_i (u inside the band,
// zero outside) and r is regressed on X_i = G u_i, so y = sum (1 + beta_i) G u_i: the gain
// each input level sees. A linear mismatch gives equal beta_i, a static nonlinearity not.
// The F statistic of "one common gain" against "five gains", scaled by the residual's
// autocorrelation (Bartlett factor c = 1 + 2 sum_k rho_r(k) rho_yhat(k), N_eff = N / c), is
// compared with chi^2(4) at alpha = 1e-4. Sign: the same with u >= 0 and u < 0 (|z| > 5).
// Direction: r regressed on [yhat, G sign(du/dt)] (play or friction); |z| > 5. The margins
// are wide because the Bartlett factor only approximates the regressors' own colour.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <vector>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::diagnose {
namespace {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

// 1 + 2 sum_k rho_a(k) rho_b(k) over k = 1..max_lag on the used samples.
double bartlett_factor(const Eigen::VectorXd& a, const Eigen::VectorXd& b, Eigen::Index lags) {
  const Eigen::Index n = a.size();
  const double aa = a.squaredNorm(), bb = b.squaredNorm();
  if (aa <= 0.0 || bb <= 0.0) return 1.0;
  double c = 1.0;
  for (Eigen::Index k = 1; k <= std::min(lags, n - 1); ++k) {
    const double ra = a.head(n - k).dot(a.tail(n - k)) / aa;
    const double rb = b.head(n - k).dot(b.tail(n - k)) / bb;
    c += 2.0 * ra * rb;
  }
  return std::max(c, 1.0);
}

}  // namespace

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

namespace {

// Least squares r = X beta on the used rows; returns beta, the residual sum of squares and
// (X'X)^-1.
struct Ls {
  Eigen::VectorXd beta;
  double rss = 0.0;
  Eigen::MatrixXd inv;
};

Ls least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& r) {
  Ls out;
  const Eigen::MatrixXd xtx = x.transpose() * x;
  out.inv = xtx.completeOrthogonalDecomposition().pseudoInverse();
  out.beta = out.inv * (x.transpose() * r);
  out.rss = (r - x * out.beta).squaredNorm();
  return out;
}

// Slow content (below the drift test's time scale) removed: a drift must not project onto
// regressors that carry a mean, such as G(u 1{u >= 0}).
Eigen::VectorXd detrend(const Problem& pr, const Eigen::VectorXd& x) {
  return x - smooth_zero_phase(x, drift_smooth_s(pr), pr.dt_s);
}

// The baseline's response to u restricted by a mask (u outside the mask set to zero).
Eigen::VectorXd masked_response(const Problem& pr, const Eigen::VectorXd& u) {
  Eigen::VectorXd z = model::simulate(pr.tf, u, pr.dt_s);
  if (pr.output_rc_s) z = signal::ac_couple(z, pr.dt_s, *pr.output_rc_s);
  return detrend(pr, z);
}

// Fewer samples than this carry no amplitude or direction test.
constexpr Eigen::Index kMinAmplitudeSamples = 64;

// chi^2(4) at 1e-4: the level tests' bound (a false alarm in 10 000 records per test).
constexpr double kLevelChi2Bound = 23.51;

// r on yh restricted to each of nb quantile bands of yh's signed level, against r on yh.
double output_level_chi2(const Eigen::VectorXd& yh, const Eigen::VectorXd& r, double n_eff,
                         int nb) {
  const Eigen::Index m = yh.size();
  std::vector<double> levels(yh.data(), yh.data() + m);
  std::vector<double> edges;
  for (int b = 1; b < nb; ++b) edges.push_back(quantile(levels, static_cast<double>(b) / nb));
  edges.push_back(std::numeric_limits<double>::infinity());
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(m, nb);
  for (Eigen::Index k = 0; k < m; ++k) {
    int b = 0;
    while (yh(k) > edges[static_cast<std::size_t>(b)]) ++b;
    x(k, b) = yh(k);
  }
  const Ls one = least_squares(yh, r), full = least_squares(x, r);
  const double s2 = full.rss / std::max(1.0, n_eff - nb);
  return (one.rss - full.rss) / std::max(s2, 1e-300);
}

// The sign of each sample's change (0 at the first).
Eigen::VectorXd direction_of(const Eigen::VectorXd& x) {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(x.size());
  for (Eigen::Index k = 1; k < x.size(); ++k)
    d(k) = x(k) > x(k - 1) ? 1.0 : (x(k) < x(k - 1) ? -1.0 : 0.0);
  return d;
}

struct DirectionFit {
  double beta = 0.0, sd = 1.0, z = 0.0;
};

// r on [yh, (the rate regressor,) the direction regressor]: the direction's coefficient
// and its z. (The test of a play is without the rate's column: a play inside a loop acts
// first as a lag, and that column would take its evidence. With it, the z is the evidence
// of a play beyond any lag: direction_beyond_lag_z.)
DirectionFit direction_fit(const Eigen::VectorXd& yh, const Eigen::VectorXd& direction,
                           const Eigen::VectorXd& r, double n_eff,
                           const Eigen::VectorXd* rate = nullptr) {
  const Eigen::Index p = rate ? 3 : 2;
  Eigen::MatrixXd x(yh.size(), p);
  x.col(0) = yh;
  if (rate) x.col(1) = *rate;
  x.col(p - 1) = direction;
  const Ls fit = least_squares(x, r);
  DirectionFit out;
  out.beta = fit.beta(p - 1);
  out.sd = std::sqrt(std::max(
      1e-300, fit.rss / std::max(1.0, n_eff - static_cast<double>(p)) * fit.inv(p - 1, p - 1)));
  out.z = out.beta / out.sd;
  return out;
}

// The first difference over dt (0 at the first sample).
Eigen::VectorXd rate_of(const Eigen::VectorXd& x, double dt_s) {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(x.size());
  for (Eigen::Index k = 1; k < x.size(); ++k) d(k) = (x(k) - x(k - 1)) / dt_s;
  return d;
}

// The rows [from, to) (to < 0: the end) past the warm-up: r and yh detrended there, and the
// effective number of samples (Bartlett); nothing when fewer than an amplitude test needs.
struct Rows {
  Eigen::Index from = 0, m = 0;
  Eigen::VectorXd r, yh;
  double n_eff = 0.0;
};
std::optional<Rows> rows_of(const Problem& pr, const Eigen::VectorXd& r_all,
                            const Eigen::VectorXd& yh_all, Eigen::Index from, Eigen::Index to) {
  const Eigen::Index n = r_all.size();
  while (from < n && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::Index m = (to < 0 ? n : std::min(to, n)) - from;
  if (m < kMinAmplitudeSamples) return std::nullopt;
  Rows rows{from, m, detrend(pr, r_all).segment(from, m), detrend(pr, yh_all).segment(from, m)};
  rows.n_eff =
      static_cast<double>(m) / bartlett_factor(rows.r, rows.yh, std::min<Eigen::Index>(200, m / 4));
  return rows;
}

}  // namespace

double direction_beyond_lag_z(const Problem& pr, const Eigen::VectorXd& r_all,
                              const Eigen::VectorXd& yh_all, Eigen::Index from, Eigen::Index to) {
  const auto rows = rows_of(pr, r_all, yh_all, from, to);
  if (!rows) return 0.0;
  const auto at = [&](const Eigen::VectorXd& x) { return x.segment(rows->from, rows->m); };
  const Eigen::VectorXd g_direction = at(masked_response(pr, direction_of(pr.u)));
  const Eigen::VectorXd g_rate = at(masked_response(pr, rate_of(pr.u, pr.dt_s)));
  return direction_fit(rows->yh, g_direction, rows->r, rows->n_eff, &g_rate).z;
}

double sign_z(const Problem& pr, const Eigen::VectorXd& r_all, const Eigen::VectorXd& yh_all,
              Eigen::Index from, Eigen::Index to) {
  const auto rows = rows_of(pr, r_all, yh_all, from, to);
  if (!rows) return 0.0;
  Eigen::MatrixXd xs(rows->m, 2);
  xs.col(0) = masked_response(pr, pr.u.cwiseMax(0.0)).segment(rows->from, rows->m);
  xs.col(1) = masked_response(pr, pr.u.cwiseMin(0.0)).segment(rows->from, rows->m);
  const Ls sign = least_squares(xs, rows->r);
  const double s2s = sign.rss / std::max(1.0, rows->n_eff - 2);
  const double var_diff = s2s * (sign.inv(0, 0) + sign.inv(1, 1) - 2.0 * sign.inv(0, 1));
  return var_diff > 0.0 ? (sign.beta(0) - sign.beta(1)) / std::sqrt(var_diff) : 0.0;
}

AmplitudeLocation locate_amplitude(const Problem& pr, const Eigen::VectorXd& r_all,
                                   const Eigen::VectorXd& yh_all) {
  AmplitudeLocation a;
  const Eigen::Index n = r_all.size();
  Eigen::Index from = 0;
  while (from < n && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::Index m = n - from;
  if (m < kMinAmplitudeSamples) return a;
  const Eigen::VectorXd r = detrend(pr, r_all).tail(m), yh = detrend(pr, yh_all).tail(m);
  const double c = bartlett_factor(r, yh, std::min<Eigen::Index>(200, m / 4));
  std::vector<double> mags;
  for (Eigen::Index k = from; k < n; ++k) mags.push_back(std::abs(pr.u(k)));
  const int nb = 5;
  std::vector<double> edges;
  for (int b = 1; b < nb; ++b) edges.push_back(quantile(mags, static_cast<double>(b) / nb));
  edges.push_back(std::numeric_limits<double>::infinity());
  // Level-band regressors X_i = G (u 1{|u| in band i}): y = sum (1 + beta_i) X_i + noise.
  Eigen::MatrixXd xl(m, nb);
  std::vector<double> level_ss(nb, 0.0), level_n(nb, 0.0);
  for (int b = 0; b < nb; ++b) {
    Eigen::VectorXd ub = Eigen::VectorXd::Zero(n);
    const double lo = b == 0 ? -1.0 : edges[static_cast<std::size_t>(b - 1)],
                 hi = edges[static_cast<std::size_t>(b)];
    for (Eigen::Index k = 0; k < n; ++k) {
      const double au = std::abs(pr.u(k));
      if (au > lo && au <= hi) {
        ub(k) = pr.u(k);
        if (k >= from)
          level_ss[static_cast<std::size_t>(b)] += au * au,
              level_n[static_cast<std::size_t>(b)] += 1.0;
      }
    }
    xl.col(b) = masked_response(pr, ub).tail(m);
  }
  const double n_eff = static_cast<double>(m) / c;
  const Ls one = least_squares(yh, r), full = least_squares(xl, r);
  const double s2 = full.rss / std::max(1.0, n_eff - nb);
  for (int b = 0; b < nb; ++b) {
    LevelBin bin;
    bin.level = std::sqrt(level_ss[static_cast<std::size_t>(b)] /
                          std::max(1.0, level_n[static_cast<std::size_t>(b)]));
    bin.gain = 1.0 + full.beta(b);
    bin.gain_std = std::sqrt(std::max(0.0, s2 * c * full.inv(b, b)) / c);
    a.by_level.push_back(bin);
  }
  a.level_chi2 = (one.rss - full.rss) / std::max(s2, 1e-300);
  // Sign: X+ = G(u 1{u >= 0}), X- = G(u 1{u < 0}).
  Eigen::MatrixXd xs(m, 2);
  xs.col(0) = masked_response(pr, pr.u.cwiseMax(0.0)).tail(m);
  xs.col(1) = masked_response(pr, pr.u.cwiseMin(0.0)).tail(m);
  const Ls sign = least_squares(xs, r);
  const double s2s = sign.rss / std::max(1.0, n_eff - 2);
  a.positive = {std::sqrt(pr.u.cwiseMax(0.0).squaredNorm() / static_cast<double>(n)),
                1 + sign.beta(0), std::sqrt(s2s * sign.inv(0, 0))};
  a.negative = {std::sqrt(pr.u.cwiseMin(0.0).squaredNorm() / static_cast<double>(n)),
                1 + sign.beta(1), std::sqrt(s2s * sign.inv(1, 1))};
  // The two gains are strongly (negatively) correlated: the contrast's own variance.
  const double var_diff = s2s * (sign.inv(0, 0) + sign.inv(1, 1) - 2.0 * sign.inv(0, 1));
  a.sign_z = var_diff > 0.0 ? (sign.beta(0) - sign.beta(1)) / std::sqrt(var_diff) : 0.0;
  // Direction: play or friction adds -b sign(du/dt) before the plant: regressor G(sign(du)),
  // beside the model output (what a gain changes).
  const Eigen::VectorXd g_direction = masked_response(pr, direction_of(pr.u)).tail(m);
  const DirectionFit in = direction_fit(yh, g_direction, r, n_eff);
  a.direction_z = in.z;
  const Eigen::VectorXd g_rate = masked_response(pr, rate_of(pr.u, pr.dt_s)).tail(m);
  a.direction_beyond_lag_z = direction_fit(yh, g_direction, r, n_eff, &g_rate).z;
  a.rising = {0.0, in.beta, in.sd};  // the play: -beta is the half-width in input units
  a.falling = {0.0, -in.beta, in.sd};
  // The output's direction: a hysteretic restoring force fed back from the output adds
  // -b sign(dz/dt) at the input: regressor G(sign(dz)).
  a.output_direction_z =
      direction_fit(yh, masked_response(pr, direction_of(yh_all)).tail(m), r, n_eff).z;
  a.output_level_chi2 = output_level_chi2(yh, r, n_eff, nb);
  a.output_level_dependent = a.output_level_chi2 > kLevelChi2Bound;
  const double spread = a.by_level.back().gain - a.by_level.front().gain;
  a.two_level_input = two_level_input(pr.u);
  a.amplitude_dependent =
      a.level_chi2 > kLevelChi2Bound && std::abs(spread) > thresholds::kAmplitudeMinSpread;
  a.sign_dependent = std::abs(a.sign_z) > thresholds::kSignDirectionZ;
  a.direction_dependent = std::abs(a.direction_z) > thresholds::kSignDirectionZ;
  a.direction_beyond_lag_dependent =
      std::abs(a.direction_beyond_lag_z) > thresholds::kSignDirectionZ;
  return a;
}

// r on [yh before the step, yh after it]: the difference of the two gains, its standard
// deviation with the residual's correlation (Bartlett) and its z; it fires when the gain
// moved significantly and by what the level's ratio says (a transducer's gain change).
StepGain locate_step_gain(const Problem& pr, const Eigen::VectorXd& r_all,
                          const Eigen::VectorXd& yh_all, double level_ratio) {
  StepGain s;
  const Eigen::Index n = r_all.size();
  Eigen::Index from = 0;
  while (from < n && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::Index m = n - from, k = pr.level_step_removed_at - from;
  if (m < 256 || k < 64 || m - k < 64) return s;
  const Eigen::VectorXd r = detrend(pr, r_all).tail(m), yh = detrend(pr, yh_all).tail(m);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(m, 2);
  x.col(0).head(k) = yh.head(k);
  x.col(1).tail(m - k) = yh.tail(m - k);
  const double n_eff =
      static_cast<double>(m) / bartlett_factor(r, yh, std::min<Eigen::Index>(200, m / 4));
  const Ls fit = least_squares(x, r);
  const double var =
      fit.rss / std::max(1.0, n_eff - 2) * (fit.inv(0, 0) + fit.inv(1, 1) - 2.0 * fit.inv(0, 1));
  s.tested = true;
  s.level_ratio = level_ratio;
  s.change = fit.beta(1) - fit.beta(0);
  s.sd = std::sqrt(std::max(var, 1e-300));
  s.z = s.change / s.sd;
  s.fires = std::abs(s.z) > thresholds::kStepGainZ &&
            std::abs(s.change - (level_ratio - 1.0)) <= thresholds::kStepGainAgreeSds * s.sd;
  return s;
}

bool two_level_input(const Eigen::VectorXd& u) {
  const Eigen::Index n = u.size();
  const double sd = std::sqrt((u.array() - u.mean()).square().mean());
  if (n < 2 || !(sd > 0.0)) return false;
  std::vector<long long> q(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k)
    q[static_cast<std::size_t>(k)] = std::llround(u(k) / (thresholds::kTwoLevelResolution * sd));
  std::sort(q.begin(), q.end());
  std::vector<Eigen::Index> runs;  // how many samples hold each value
  for (std::size_t i = 0; i < q.size();) {
    std::size_t j = i;
    while (j < q.size() && q[j] == q[i]) ++j;
    runs.push_back(static_cast<Eigen::Index>(j - i));
    i = j;
  }
  std::sort(runs.rbegin(), runs.rend());
  const Eigen::Index top = runs[0] + (runs.size() > 1 ? runs[1] : 0);
  return static_cast<double>(top) >= thresholds::kTwoLevelShare * static_cast<double>(n);
}

}  // namespace rig::diagnose
