#include "rig/ident/quality.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace rig::ident {
namespace {

using Eigen::Index;
using Eigen::VectorXd;

// Correlations of the mean-removed record: the analysis window (-z..P) for y and u, and
// symmetric auto-correlations out to lag 2L-2 for the Toeplitz matrix and the spectra.
struct Correlations {
  signal::Correlation ryu;
  signal::Correlation ruu_long, ryy_long;  // zero at L-1, lags -(L-1)..(L-1)... doubled
  double products = 1.0;                   // N' of the window correlator
  double ruu(Index lag) const { return ruu_long.r[ruu_long.zero_index + std::abs(lag)]; }
  double ryy(Index lag) const { return ryy_long.r[ryy_long.zero_index + std::abs(lag)]; }
};

Correlations correlate(const VectorXd& u, const VectorXd& y, signal::CorrelatorOptions opt) {
  opt.kind = signal::CorrelatorKind::kFft;
  opt.skip = 1;
  opt.arcsine_correction = false;
  opt.zero_index = signal::resolved_zero_index(opt);
  Correlations c;
  c.ryu = signal::cross_correlation(y, u, opt);
  c.products = double(signal::products_per_lag(opt, u.size()));
  signal::CorrelatorOptions wide = opt;
  wide.lags = 4 * opt.lags - 3;  // lags -(2L-2)..(2L-2)
  wide.zero_index = 2 * opt.lags - 2;
  c.ruu_long = signal::auto_correlation(u, wide);
  c.ryy_long = signal::auto_correlation(y, wide);
  return c;
}

// Bartlett's standard deviation of a cross-correlation coefficient between two independent
// series: var rho(k) = (1/N') sum_j rho_uu(j) rho_yy(j).
double bartlett_sigma(const Correlations& c, Index max_lag) {
  double sum = 0.0;
  for (Index j = -max_lag; j <= max_lag; ++j) sum += c.ruu(j) * c.ryy(j) / (c.ruu(0) * c.ryy(0));
  return std::sqrt(std::max(sum, 1.0) / c.products);
}

// Regularised Wiener-Hopf impulse response over the window's lags (see the header).
VectorXd impulse_response(const Correlations& c, double lambda) {
  const Index n = c.ryu.size();
  Eigen::MatrixXd r(n, n);
  for (Index i = 0; i < n; ++i) {
    for (Index j = 0; j < n; ++j) r(i, j) = c.ruu(i - j);
  }
  r.diagonal().array() += lambda * c.ruu(0);
  return r.ldlt().solve(c.ryu.r);
}

// Participation ratio of the Blackman-Tukey spectrum (Bartlett lag window, so S >= 0):
// N_eff = (sum S)^2 / sum S^2 bins. One sinusoid occupies about two to three bins.
double excited_lines(const Correlations& c, Index m) {
  VectorXd s(m + 1);
  for (Index j = 0; j <= m; ++j) {
    double v = c.ruu(0);
    for (Index k = 1; k <= m; ++k) {
      v += 2.0 * (1.0 - double(k) / double(m + 1)) * c.ruu(k) *
           std::cos(std::numbers::pi * double(j * k) / double(m));
    }
    s[j] = std::max(v, 0.0);
  }
  const double sq = s.squaredNorm();
  return sq > 0.0 ? s.sum() * s.sum() / sq / 2.0 : 0.0;
}

void add(QualityReport& rep, std::string name, Severity sev, std::string msg, double value,
         double threshold) {
  rep.flags.push_back({std::move(name), sev, std::move(msg), value, threshold});
}

void check_clipping(const VectorXd& x, const char* channel, const QualityOptions& o,
                    QualityReport& rep) {
  const double hi = x.maxCoeff(), lo = x.minCoeff();
  const double tol = 1e-9 * std::max(hi - lo, 1e-300);
  const double n = double(x.size());
  const double f_hi = double((x.array() >= hi - tol).count()) / n;
  const double f_lo = double((x.array() <= lo + tol).count()) / n;
  const double worst = std::max(f_hi, f_lo);
  rep.figures.emplace_back(std::string(channel) + "_clip_fraction", worst);
  // A two-level signal (PRBS) lives at its extremes by design.
  if (hi == lo || f_hi + f_lo > 0.9 || worst < o.clip_warning) return;
  add(rep, std::string(channel) + "_clipped", worst >= o.clip_fatal ? Severity::kFatal : Severity::kWarning,
      fmt::format("{:.1f} % of the {} samples sit at its {} ({:.6g}): the channel is clipped or "
                  "saturated; reduce the excitation amplitude or check the transducer range.",
                  100.0 * worst, channel, f_hi >= f_lo ? "maximum" : "minimum",
                  f_hi >= f_lo ? hi : lo),
      worst, o.clip_warning);
}

void check_sampling(double dt_s, const QualityOptions& o, QualityReport& rep) {
  const double ratio = o.jitter_max_s / dt_s;
  rep.figures.emplace_back("jitter_ratio", ratio);
  if (ratio <= o.jitter_warning) return;
  add(rep, "non_uniform_sampling", ratio >= o.jitter_fatal ? Severity::kFatal : Severity::kWarning,
      fmt::format("Sample times deviate by up to {:.1f} % of the sample period ({:.3g} s): the "
                  "recording was not sampled uniformly; check the logger clock and link.",
                  100.0 * ratio, o.jitter_max_s),
      ratio, o.jitter_warning);
}

void check_coupled_pairs(double dt_s, const QualityOptions& o, QualityReport& rep) {
  std::vector<std::pair<std::string, double>> rcs;
  for (const CoupledPair& p : o.coupled_pairs) {
    const double rc = fitted_coupling_rc_s(p.raw, p.coupled, dt_s);
    rep.figures.emplace_back("coupling_rc_" + p.name + "_s", rc);
    if (std::isfinite(rc)) rcs.emplace_back(p.name, rc);
  }
  if (rcs.size() >= 2) {
    const auto [mn, mx] = std::minmax_element(rcs.begin(), rcs.end(), [](auto& a, auto& b) { return a.second < b.second; });
    if (mx->second / mn->second - 1.0 > o.coupling_tolerance) {
      add(rep, "coupling_mismatch", Severity::kFatal,
          fmt::format("The AC-coupling time constants of the channels differ ({} {:.3g} s, {} "
                      "{:.3g} s): pass both channels through matched networks, or the model "
                      "will contain the ratio of the two.",
                      mn->first, mn->second, mx->first, mx->second),
          mx->second / mn->second, 1.0 + o.coupling_tolerance);
      return;
    }
  }
  if (!o.coupling_rc_s) return;
  for (const auto& [name, rc] : rcs) {
    if (std::abs(rc / *o.coupling_rc_s - 1.0) > o.coupling_tolerance) {
      add(rep, "coupling_mismatch", Severity::kWarning,
          fmt::format("Channel {} behaves like an AC coupling with RC = {:.3g} s, but the "
                      "recording declares {:.3g} s: check the coupling network or the sidecar.",
                      name, rc, *o.coupling_rc_s),
          rc, *o.coupling_rc_s);
      return;
    }
  }
}

}  // namespace
