// Amplitude location of the residual r = y - yhat.
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
#include <optional>
#include <vector>

#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/residual_stats.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {
namespace {

// chi^2(4) at 1e-4: the level tests' bound (a false alarm in 10 000 records per test).
constexpr double kLevelChi2Bound = 23.51;
// The level tests' quantile bands (chi^2 with kLevelBands - 1 degrees of freedom).
constexpr int kLevelBands = 5;

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

// r on [G(u 1{u >= 0}), G(u 1{u < 0})] over the rows: the two gains (beside 1), their
// variances and the z of their difference (the two are strongly, negatively, correlated: the
// contrast's own variance).
struct SignFit {
  Ls fit;
  double s2 = 0.0, z = 0.0;
};
SignFit sign_fit(const Problem& pr, const Rows& rows) {
  Eigen::MatrixXd xs(rows.m, 2);
  xs.col(0) = rows.of(masked_response(pr, pr.u.cwiseMax(0.0)));
  xs.col(1) = rows.of(masked_response(pr, pr.u.cwiseMin(0.0)));
  SignFit out{least_squares(xs, rows.r)};
  out.s2 = out.fit.rss / std::max(1.0, rows.n_eff - 2);
  const Ls& f = out.fit;
  const double var_diff = out.s2 * (f.inv(0, 0) + f.inv(1, 1) - 2.0 * f.inv(0, 1));
  out.z = var_diff > 0.0 ? (f.beta(0) - f.beta(1)) / std::sqrt(var_diff) : 0.0;
  return out;
}

// The level test on the rows: r on the five level bands' responses X_i = G(u 1{|u| in band
// i}) (the bands the rows' quantiles of |u|), against r on yh (one common gain).
LevelTest level_test_on(const Problem& pr, const Rows& rows) {
  const Eigen::Index n = pr.u.size(), to = rows.from + rows.m;
  std::vector<double> mags;
  for (Eigen::Index k = rows.from; k < to; ++k) mags.push_back(std::abs(pr.u(k)));
  std::vector<double> edges;
  for (int b = 1; b < kLevelBands; ++b)
    edges.push_back(quantile(mags, static_cast<double>(b) / kLevelBands));
  edges.push_back(std::numeric_limits<double>::infinity());
  Eigen::MatrixXd xl(rows.m, kLevelBands);
  std::vector<double> level_ss(kLevelBands, 0.0), level_n(kLevelBands, 0.0);
  for (int b = 0; b < kLevelBands; ++b) {
    const auto bi = static_cast<std::size_t>(b);
    Eigen::VectorXd ub = Eigen::VectorXd::Zero(n);
    const double lo = b == 0 ? -1.0 : edges[bi - 1], hi = edges[bi];
    for (Eigen::Index k = 0; k < n; ++k) {
      const double au = std::abs(pr.u(k));
      if (!(au > lo && au <= hi)) continue;
      ub(k) = pr.u(k);
      if (k >= rows.from && k < to) level_ss[bi] += au * au, level_n[bi] += 1.0;
    }
    xl.col(b) = rows.of(masked_response(pr, ub));
  }
  const double c = rows.c;
  const Ls one = least_squares(rows.yh, rows.r), full = least_squares(xl, rows.r);
  const double s2 = full.rss / std::max(1.0, rows.n_eff - kLevelBands);
  LevelTest out;
  for (int b = 0; b < kLevelBands; ++b) {
    const auto bi = static_cast<std::size_t>(b);
    out.by_level.push_back({std::sqrt(level_ss[bi] / std::max(1.0, level_n[bi])),
                            1.0 + full.beta(b),
                            std::sqrt(std::max(0.0, s2 * c * full.inv(b, b)) / c)});
  }
  out.chi2 = (one.rss - full.rss) / std::max(s2, 1e-300);
  return out;
}

}  // namespace

bool LevelTest::exceeds(double chi2_bound) const {
  return by_level.size() >= 2 && chi2 > chi2_bound &&
         std::abs(by_level.back().gain - by_level.front().gain) > thresholds::kAmplitudeMinSpread;
}

bool LevelTest::fires() const { return exceeds(kLevelChi2Bound); }

LevelTest level_test(const Problem& pr, const Eigen::VectorXd& r_all, const Eigen::VectorXd& yh_all,
                     Eigen::Index from, Eigen::Index to) {
  const auto rows = rows_of(pr, r_all, yh_all, from, to);
  return rows ? level_test_on(pr, *rows) : LevelTest{};
}

double direction_beyond_lag_z(const Problem& pr, const Eigen::VectorXd& r_all,
                              const Eigen::VectorXd& yh_all, Eigen::Index from, Eigen::Index to) {
  const auto rows = rows_of(pr, r_all, yh_all, from, to);
  if (!rows) return 0.0;
  const Eigen::VectorXd g_direction = rows->of(masked_response(pr, direction_of(pr.u)));
  const Eigen::VectorXd g_rate = rows->of(masked_response(pr, rate_of(pr.u, pr.dt_s)));
  return direction_fit(rows->yh, g_direction, rows->r, rows->n_eff, &g_rate).z;
}

double direction_z(const Problem& pr, const Eigen::VectorXd& r_all, const Eigen::VectorXd& yh_all,
                   Eigen::Index from, Eigen::Index to) {
  const auto rows = rows_of(pr, r_all, yh_all, from, to);
  if (!rows) return 0.0;
  const Eigen::VectorXd g_direction = rows->of(masked_response(pr, direction_of(pr.u)));
  return direction_fit(rows->yh, g_direction, rows->r, rows->n_eff).z;
}

double sign_z(const Problem& pr, const Eigen::VectorXd& r_all, const Eigen::VectorXd& yh_all,
              Eigen::Index from, Eigen::Index to) {
  const auto rows = rows_of(pr, r_all, yh_all, from, to);
  return rows ? sign_fit(pr, *rows).z : 0.0;
}

AmplitudeLocation locate_amplitude(const Problem& pr, const Eigen::VectorXd& r_all,
                                   const Eigen::VectorXd& yh_all) {
  AmplitudeLocation a;
  const auto rows = rows_of(pr, r_all, yh_all, 0, -1);
  if (!rows) return a;
  const Eigen::VectorXd &r = rows->r, &yh = rows->yh;
  const double n_eff = rows->n_eff, n = static_cast<double>(pr.u.size());
  const LevelTest level = level_test_on(pr, *rows);
  a.by_level = level.by_level;
  a.level_chi2 = level.chi2;
  // Sign: X+ = G(u 1{u >= 0}), X- = G(u 1{u < 0}).
  const SignFit sign = sign_fit(pr, *rows);
  a.positive = {std::sqrt(pr.u.cwiseMax(0.0).squaredNorm() / n), 1 + sign.fit.beta(0),
                std::sqrt(sign.s2 * sign.fit.inv(0, 0))};
  a.negative = {std::sqrt(pr.u.cwiseMin(0.0).squaredNorm() / n), 1 + sign.fit.beta(1),
                std::sqrt(sign.s2 * sign.fit.inv(1, 1))};
  a.sign_z = sign.z;
  // Direction: play or friction adds -b sign(du/dt) before the plant: regressor G(sign(du)),
  // beside the model output (what a gain changes).
  const Eigen::VectorXd g_direction = rows->of(masked_response(pr, direction_of(pr.u)));
  const DirectionFit in = direction_fit(yh, g_direction, r, n_eff);
  a.direction_z = in.z;
  const Eigen::VectorXd g_rate = rows->of(masked_response(pr, rate_of(pr.u, pr.dt_s)));
  a.direction_beyond_lag_z = direction_fit(yh, g_direction, r, n_eff, &g_rate).z;
  a.rising = {0.0, in.beta, in.sd};  // the play: -beta is the half-width in input units
  a.falling = {0.0, -in.beta, in.sd};
  // The output's direction: a hysteretic restoring force fed back from the output adds
  // -b sign(dz/dt) at the input: regressor G(sign(dz)).
  a.output_direction_z =
      direction_fit(yh, rows->of(masked_response(pr, direction_of(yh_all))), r, n_eff).z;
  a.output_level_chi2 = output_level_chi2(yh, r, n_eff, kLevelBands);
  a.output_level_dependent = a.output_level_chi2 > kLevelChi2Bound;
  a.two_level_input = two_level_input(pr.u);
  a.amplitude_dependent = level.fires();
  a.sign_dependent = std::abs(a.sign_z) > thresholds::kSignDirectionZ;
  a.direction_dependent = std::abs(a.direction_z) > thresholds::kSignDirectionZ;
  a.direction_beyond_lag_dependent =
      std::abs(a.direction_beyond_lag_z) > thresholds::kSignDirectionZ;
  return a;
}

// r on [yh before the step, yh after it]: the difference of the two gains, its standard
// deviation with the residual's correlation (Bartlett) and its z; it fires when the gain
// moved by what the level's ratio says, and that reading is much likelier than no change
// (a transducer's gain change).
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
  // Generalised least squares: the residual's colour (a drift, the grid's wander) is taken
  // out by an AR whitener fitted to the first fit's residual, then the fit is repeated.
  const GlsFit gls =
      gls_fit(x, r, yh, thresholds::kWhitenOrder, std::min<Eigen::Index>(200, m / 4));
  const Ls& fit = gls.fit;
  const double var = gls.s2 * (fit.inv(0, 0) + fit.inv(1, 1) - 2.0 * fit.inv(0, 1));
  s.tested = true;
  s.level_ratio = level_ratio;
  s.change = fit.beta(1) - fit.beta(0);
  s.sd = std::sqrt(std::max(var, 1e-300));
  s.z = s.change / s.sd;
  const double z_level = (s.change - (level_ratio - 1.0)) / s.sd;
  s.log_likelihood_ratio = 0.5 * (s.z * s.z - z_level * z_level);
  s.fires = std::abs(z_level) <= thresholds::kStepGainAgreeSds &&
            s.log_likelihood_ratio >= std::log(thresholds::kStepGainLikelihoodRatio);
  s.decisive = s.fires && std::abs(s.z) > thresholds::kStepGainZ;
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
