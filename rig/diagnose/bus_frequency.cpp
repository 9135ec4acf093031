#include "rig/diagnose/bus_frequency.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <complex>
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
  s.note = fmt::format(
      "the grid's share through the bus frequency ({:.3g} Hz rms; {:.3g} output units rms, "
      "{:.0f} % of the model's residual) is taken out first",
      s.frequency_rms_hz, s.share_rms, 100.0 * s.residual_share);
  return s;
}

}  // namespace rig::diagnose
