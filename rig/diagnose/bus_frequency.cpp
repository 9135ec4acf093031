#include "rig/diagnose/bus_frequency.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include "rig/diagnose/augmented_model.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/split.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/fra/h1.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::diagnose {
namespace {

using thresholds::kBusFrequencyLagsS, thresholds::kBusFrequencyMaxBiasCoherence;

// A first-order lag of time constant tau_s, settled at the first sample.
Eigen::VectorXd lag(const Eigen::VectorXd& x, double dt_s, double tau_s) {
  const double a = std::exp(-dt_s / tau_s);
  Eigen::VectorXd out(x.size());
  double v = x.size() > 0 ? x(0) : 0.0;
  for (Eigen::Index k = 0; k < x.size(); ++k) out(k) = v = a * v + (1.0 - a) * x(k);
  return out;
}

// x, x through each lag, and the rate of change of x through the first lag (columns).
Eigen::MatrixXd lagged_basis(const Eigen::VectorXd& x, double dt_s) {
  const Eigen::Index n = x.size(), nl = std::ssize(kBusFrequencyLagsS);
  Eigen::MatrixXd b(n, nl + 2);
  b.col(0) = x;
  for (Eigen::Index j = 0; j < nl; ++j) b.col(1 + j) = lag(x, dt_s, kBusFrequencyLagsS[j]);
  b(0, nl + 1) = 0.0;
  for (Eigen::Index k = 1; k < n; ++k) b(k, nl + 1) = (b(k, 1) - b(k - 1, 1)) / dt_s;
  return b;
}

struct Regression {
  Eigen::VectorXd coef;  // without the constant
  double r2 = 0.0;
};

// Least squares of y on [1, X] over the samples with weight > 0.
Regression regress(const Eigen::VectorXd& y, const Eigen::MatrixXd& x, const Eigen::ArrayXd& w) {
  const Eigen::Index m = (w > 0.0).count();
  Eigen::MatrixXd a(m, x.cols() + 1);
  Eigen::VectorXd b(m);
  for (Eigen::Index k = 0, i = 0; k < y.size(); ++k) {
    if (!(w(k) > 0.0)) continue;
    a(i, 0) = 1.0, a.row(i).tail(x.cols()) = x.row(k), b(i++) = y(k);
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  const double ss = (b.array() - b.mean()).square().sum();
  Regression r{c.tail(x.cols()), 0.0};
  if (ss > 0.0) r.r2 = 1.0 - (b - a * c).squaredNorm() / ss;
  return r;
}

// The bias's coherence with the frequency, averaged over the bins where the bias has at
// least kBusFrequencyBandShare of its peak power.
double band_coherence(const Eigen::VectorXd& u, const Eigen::VectorXd& f, double dt_s) {
  fra::WelchOptions wo;
  wo.segment_length =
      std::max<Eigen::Index>(8, 2 * u.size() / (thresholds::kBusFrequencySegments + 1));
  const fra::CrossSpectra c = fra::welch_cross_spectra(u, f, dt_s, wo);
  const double peak = c.guu.maxCoeff();
  double sum = 0.0;
  int bins = 0;
  for (Eigen::Index k = 0; k < c.guu.size(); ++k) {
    if (c.freq_hz(k) <= 0.0 || c.guu(k) < thresholds::kBusFrequencyBandShare * peak) continue;
    const double den = c.guu(k) * c.gyy(k);
    sum += den > 0.0 ? std::norm(c.gyu(k)) / den : 0.0;
    ++bins;
  }
  return bins > 0 ? sum / bins : 0.0;
}

// The share's coefficients, fitted where the grid's wander is and a drift or an operating
// point step is not: residual and basis through the same high-pass (kBusFrequencyHighPassS),
// beside the step of an operating point found in the residual (a gain change from half-way
// steps the level by (g - 1) x level, which slow regressors would otherwise fit in part).
Eigen::VectorXd grid_coefficients(const Problem& pr, const Eigen::VectorXd& residual,
                                  const Eigen::MatrixXd& phi, const Eigen::ArrayXd& used) {
  const Eigen::Index step_at = find_level_shift(pr, residual);
  Eigen::MatrixXd x(phi.rows(), phi.cols() + (step_at >= 0 ? 1 : 0));
  x.leftCols(phi.cols()) = phi;
  if (step_at >= 0) {
    x.col(phi.cols()).setZero();
    x.col(phi.cols()).tail(phi.rows() - step_at).setOnes();
  }
  const double hp = thresholds::kBusFrequencyHighPassS;
  for (Eigen::Index j = 0; j < x.cols(); ++j) x.col(j) = signal::ac_couple(x.col(j), pr.dt_s, hp);
  return regress(signal::ac_couple(residual, pr.dt_s, hp), x, used).coef.head(phi.cols());
}

// x through the band where the grid's answer through the governor is (thresholds.hpp
// kReferredBandS): above a drift's time scale, below the governor's and the swing's dynamics.
Eigen::VectorXd referral_band(const Eigen::VectorXd& x, double dt_s) {
  const auto [high_pass_s, low_pass_s] = thresholds::kReferredBandS;
  return lag(lag(signal::ac_couple(x, dt_s, high_pass_s), dt_s, low_pass_s), dt_s, low_pass_s);
}

// The grid's frequency enters a speed governor where the bias does, on its speed error: a set
// in droop R at f0 answers df as a bias of a df, a = -100 / (R f0) % per Hz. In the band where
// that path is the model's own response (referral_band), the residual is a G f: a from a
// regression on G f alone, its standard error from the band's degrees of freedom. Referred to
// the input (u + a f), an effect inside the governor's loop sees what its actuator saw (a rack
// stop hit by the grid's wander, not by the bias alone); y gains a G f, so that the baseline's
// residual is unchanged. Only where a is a droop a set can have, is measured well, and moves
// the governor's input by a share of what the bias does (thresholds.hpp).
void refer_to_input(DiagnoseInput& in, const Problem& pr, const Eigen::VectorXd& f, double f0,
                    const Eigen::VectorXd& residual, const Eigen::ArrayXd& used,
                    BusFrequencyShare& s) {
  Problem pf = pr;
  pf.u = f;
  finish_problem(pf);
  Eigen::VectorXd gf = pf.baseline_z;
  if (pr.output_rc_s) gf = signal::ac_couple(gf, pr.dt_s, *pr.output_rc_s);
  const Eigen::ArrayXd rb = referral_band(residual, pr.dt_s).array() * used;
  const Eigen::ArrayXd gb = referral_band(gf, pr.dt_s).array() * used;
  const double sgg = gb.square().sum();
  if (!(sgg > 0.0)) return;
  const double a = (rb * gb).sum() / sgg;
  const double m = used.sum();
  const double band_hz = 1.0 / (2.0 * std::numbers::pi * thresholds::kReferredBandS.second);
  const double dof = std::max(1.0, 2.0 * band_hz * m * pr.dt_s);
  const double se = std::sqrt((rb - a * gb).square().sum() / m / (sgg / m) / dof);
  s.input_per_hz = a;
  s.input_per_hz_se = se;
  if (f0 > 0.0 && a < 0.0) s.droop_pct = -100.0 / (a * f0) * 100.0;  // else no droop (0)
  const double share = std::abs(a) * s.frequency_rms_hz / pr.scales.u_std;
  const auto [droop_lo, droop_hi] = thresholds::kReferredDroopPct;
  if (!(a < 0.0) || !(s.droop_pct >= droop_lo && s.droop_pct <= droop_hi) ||
      std::abs(a) < thresholds::kReferredMinZ * se || share < thresholds::kReferredMinShare)
    return;
  s.referred = true;
  in.u += a * f;
  in.y += a * gf;
}

void check(const DiagnoseInput& in, const Eigen::VectorXd& f) {
  if (f.size() != in.y.size())
    throw std::invalid_argument(
        fmt::format("bus frequency: {} samples against the output's {}", f.size(), in.y.size()));
  for (Eigen::Index k = 0; k < f.size(); ++k)
    if (!std::isfinite(f(k)))
      throw std::invalid_argument(
          fmt::format("bus frequency: sample {} is not a finite number", k));
}

}  // namespace

BusFrequencyShare take_out_bus_frequency(DiagnoseInput& in, const Eigen::VectorXd& freq_hz) {
  check(in, freq_hz);
  BusFrequencyShare s;
  int blocks = 0;
  Eigen::Index warmup = 0;
  const Problem pr = prepare_problem(in, &blocks, &warmup);
  const Eigen::ArrayXd used = pr.est_weight + pr.val_weight;
  const Eigen::VectorXd f = freq_hz.array() - freq_hz.mean();
  s.frequency_rms_hz = std::sqrt(f.squaredNorm() / static_cast<double>(f.size()));
  if (!(s.frequency_rms_hz > 0.0)) {
    return s;  // constant (a stiff grid, or none recorded): nothing to take out, nothing to say
  }
  s.bias_coherence = band_coherence(pr.u, f, pr.dt_s);
  if (s.bias_coherence > kBusFrequencyMaxBiasCoherence) {
    s.note = fmt::format(
        "the bus frequency follows the bias (coherence {:.2f} over the excited band): the set "
        "sets its own frequency (islanded), so it is not taken as the grid's",
        s.bias_coherence);
    return s;
  }
  if (pr.output_clip.side != 0) {
    s.note = "the output is clipped: the grid's share is not taken out of a clipped record";
    return s;
  }
  Eigen::MatrixXd phi = lagged_basis(f, pr.dt_s);
  if (pr.output_rc_s)
    for (Eigen::Index j = 0; j < phi.cols(); ++j)
      phi.col(j) = signal::ac_couple(phi.col(j), pr.dt_s, *pr.output_rc_s);
  const Eigen::VectorXd residual = pr.y - model_output(pr, {}).yhat;
  const Eigen::VectorXd share = phi * grid_coefficients(pr, residual, phi, used);
  in.y -= share;
  s.used = true;
  const auto variance = [&](const Eigen::VectorXd& v) {
    const Eigen::ArrayXd x = v.array() * used;
    const double m = x.sum() / used.sum();
    return ((v.array() - m).square() * used).sum();
  };
  const double vr = variance(residual);
  s.residual_share = vr > 0.0 ? std::max(0.0, 1.0 - variance(residual - share) / vr) : 0.0;
  if ((s.event_at = find_level_shift(pr, share, thresholds::kGridEventSpreads)) > 0) {
    const Eigen::Index n = share.size(), at = s.event_at;
    s.event_step = share.tail(n - at).mean() - share.head(at).mean();
  }
  const Eigen::VectorXd sc = share.array() - share.mean();
  s.share_rms = std::sqrt(sc.squaredNorm() / static_cast<double>(sc.size()));
  // Not across a grid event: it moves the operating point by more than the small signal the
  // model holds for (the event is the level's step, taken out as such).
  if (s.event_at <= 0) refer_to_input(in, pr, f, freq_hz.mean(), residual, used, s);
  s.note = fmt::format(
      "the grid's share through the bus frequency ({:.3g} Hz rms; {:.3g} output units rms, "
      "{:.0f} % of the model's residual) is taken out first",
      s.frequency_rms_hz, s.share_rms, 100.0 * s.residual_share);
  if (s.referred)
    s.note += fmt::format(
        "; it reaches the governor's input as {:.3g} input units per Hz (a {:.2g} % droop when "
        "the input is % of rated power), so effects inside the loop are fitted on the bias and "
        "the grid together",
        s.input_per_hz, s.droop_pct);
  return s;
}

}  // namespace rig::diagnose
