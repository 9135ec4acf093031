#include "rig/ident/quality.hpp"

// rig_ident does not link libfmt; the header-only build keeps the messages readable.
#define FMT_HEADER_ONLY
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

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
  const ExtremePile p = extreme_pile(x);
  const double hi = p.hi, lo = p.lo;
  const double n = double(x.size());
  const double f_hi = double(p.at_hi) / n;
  const double f_lo = double(p.at_lo) / n;
  const double worst = std::max(f_hi, f_lo);
  rep.figures.emplace_back(std::string(channel) + "_clip_fraction", worst);
  // A two-level signal (PRBS) lives at its extremes by design.
  if (hi == lo || f_hi + f_lo > 0.9 || worst < o.clip_warning) return;
  add(rep, std::string(channel) + "_clipped",
      worst >= o.clip_fatal ? Severity::kFatal : Severity::kWarning,
      fmt::format("{:.1f} % of the {} samples sit at its {} ({:.6g}): the channel is clipped or "
                  "saturated; reduce the excitation amplitude or check the transducer range.",
                  100.0 * worst, channel, f_hi >= f_lo ? "maximum" : "minimum",
                  f_hi >= f_lo ? hi : lo),
      worst, o.clip_warning);
}

}  // namespace

ExtremePile extreme_pile(const VectorXd& x) {
  ExtremePile p;
  if (x.size() == 0) return p;
  std::vector<double> v(x.data(), x.data() + x.size());
  std::sort(v.begin(), v.end());
  p.lo = v.front(), p.hi = v.back();
  const double tol = 1e-9 * std::max(p.hi - p.lo, 1e-300);
  std::vector<Index> runs;  // counts of the distinct values, ascending
  for (std::size_t i = 0, j = 0; i < v.size(); i = j) {
    while (j < v.size() && v[j] - v[i] <= tol) ++j;
    runs.push_back(static_cast<Index>(j - i));
  }
  p.at_lo = runs.front(), p.at_hi = runs.back();
  const std::size_t k = std::min(kExtremeNeighbours, runs.size() - 1);
  for (std::size_t i = 1; i <= k; ++i) {
    p.near_lo = std::max(p.near_lo, runs[i]);
    p.near_hi = std::max(p.near_hi, runs[runs.size() - 1 - i]);
  }
  return p;
}

namespace {

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
    const auto [mn, mx] = std::minmax_element(rcs.begin(), rcs.end(),
                                              [](auto& a, auto& b) { return a.second < b.second; });
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

namespace {

// Undecayed: |r_yu| over the last tenth of the positive lags against its peak.
void check_decay(const Correlations& c, const VectorXd& rho, double sigma, const QualityOptions& o,
                 QualityReport& rep) {
  const Index n = c.ryu.size(), p = n - 1 - c.ryu.zero_index;
  const Index tail_n = std::max<Index>(3, p / 10);
  const double pos_peak = rho.tail(p + 1).cwiseAbs().maxCoeff();
  const double tail = rho.tail(tail_n).cwiseAbs().maxCoeff();
  rep.figures.emplace_back("tail_ratio", tail / pos_peak);
  if (tail / pos_peak > o.undecayed_ratio && tail > 3.0 * sigma) {
    add(rep, "undecayed", Severity::kWarning,
        fmt::format("The cross-correlation is still at {:.0f} % of its peak at the end of the "
                    "lag window ({:.3g} s): lengthen the window (--lags), remove drift from the "
                    "recording, or check that both channels have the same AC coupling.",
                    100.0 * tail / pos_peak, c.ryu.lag_s(n - 1)),
        tail / pos_peak, o.undecayed_ratio);
  }
}

// Sag: the step response s = cumulative sum of h over lags >= 0, its last quarter's mean
// against its largest excursion. A type-0 plant settles near its peak; an output that is
// AC coupled alone returns towards zero (a slow opposite-sign tail in h).
void check_sag(const VectorXd& h, Index z, const QualityOptions& o, QualityReport& rep) {
  const Index p = h.size() - 1 - z;
  VectorXd s(p + 1);
  double acc = 0.0;
  for (Index k = 0; k <= p; ++k) s[k] = (acc += h[z + k]);
  Index ipk = 0;
  s.cwiseAbs().maxCoeff(&ipk);
  const Index q = std::max<Index>(2, (p + 1) / 4);
  const double step_tail = s.tail(q).mean() * (s[ipk] >= 0 ? 1.0 : -1.0) / std::abs(s[ipk]);
  rep.figures.emplace_back("step_tail_ratio", step_tail);
  if (step_tail < o.sag_ratio && !rep.find("coupling_mismatch")) {
    add(rep, "coupling_mismatch", Severity::kWarning,
        fmt::format(
            "The step response derived from the data falls back to {:.0f} % of its "
            "peak within the window (a slow opposite-sign tail): the output is probably "
            "AC coupled without a matched network on the input{}.",
            100.0 * step_tail,
            o.coupling_rc_s ? fmt::format(" (declared RC {:.3g} s)", *o.coupling_rc_s) : ""),
        step_tail, o.sag_ratio);
  }
}

// The checks that need the correlations; skipped after no_response (nothing to judge).
void check_response(const Correlations& c, const QualityOptions& o, QualityReport& rep) {
  const Index z = c.ryu.zero_index, n = c.ryu.size();
  const double scale = std::sqrt(c.ruu(0) * c.ryy(0));
  const double sigma = bartlett_sigma(c, n - 1);
  const VectorXd rho = scale > 0.0 ? VectorXd(c.ryu.r / scale) : VectorXd::Zero(n);
  const double peak_sigma = rho.cwiseAbs().maxCoeff() / sigma;
  rep.figures.emplace_back("peak_sigma", peak_sigma);
  if (!(peak_sigma >= o.significance_sigma)) {
    add(rep, "no_response", Severity::kFatal,
        fmt::format("No significant cross-correlation between input and output (peak {:.1f} "
                    "standard deviations, {:.0f} needed): the output does not respond to the "
                    "excitation; check that the excitation is connected and that the input and "
                    "output columns are the right channels.",
                    peak_sigma, o.significance_sigma),
        peak_sigma, o.significance_sigma);
    return;
  }
  // The deconvolution is ill-conditioned for a strongly coloured input, so a fatal verdict
  // also needs the raw cross-correlation's peak at a negative lag.
  Index peak_at = 0;
  rho.cwiseAbs().maxCoeff(&peak_at);
  rep.figures.emplace_back("peak_lag_s", c.ryu.lag_s(peak_at));
  const VectorXd h = impulse_response(c, o.regularisation);
  const double acausal = h.head(z).squaredNorm() / h.squaredNorm();
  rep.figures.emplace_back("acausal_fraction", acausal);
  const bool fatal = acausal > o.acausal_fatal && peak_at < z;
  if (acausal > o.acausal_warning) {
    add(rep, "acausal", fatal ? Severity::kFatal : Severity::kWarning,
        fatal ? fmt::format("{:.0f} % of the impulse response lies at negative lags (the output "
                            "moves before the input): the input and output channels are probably "
                            "swapped, or their time stamps are skewed.",
                            100.0 * acausal)
              : fmt::format("{:.0f} % of the impulse response deconvolved from the correlations "
                            "lies at negative lags although the cross-correlation peaks at a "
                            "positive lag: check the channel order and time stamps; a strongly "
                            "coloured input or a short lag window also causes this.",
                            100.0 * acausal),
        acausal, o.acausal_warning);
    if (fatal) return;
  }
  check_decay(c, rho, sigma, o, rep);
  check_sag(h, z, o, rep);
}

void check_excitation(const Correlations& c, const QualityOptions& o, QualityReport& rep) {
  const double lines = excited_lines(c, c.ryu.size() - 1);
  const int unknowns = o.order.n + o.order.m + 1 + (o.delay_estimated ? 1 : 0);
  const int required = (unknowns + 1) / 2;
  rep.figures.emplace_back("excited_lines", lines);
  rep.figures.emplace_back("required_lines", required);
  if (lines >= required) return;
  add(rep, "not_persistently_exciting", Severity::kFatal,
      fmt::format(
          "The input excites only about {:.1f} independent frequencies, but a {}/{} model{} "
          "needs at least {}: use a broadband excitation (filtered noise or PRBS) or ask "
          "for a lower order.",
          lines, o.order.n, o.order.m, o.delay_estimated ? " with a delay" : "", required),
      lines, required);
}

}  // namespace

const char* to_string(Severity severity) {
  return severity == Severity::kFatal ? "fatal" : "warning";
}

bool QualityReport::has_fatal() const {
  return std::any_of(flags.begin(), flags.end(),
                     [](const QualityFlag& f) { return f.severity == Severity::kFatal; });
}

const QualityFlag* QualityReport::find(const std::string& name) const {
  for (const QualityFlag& f : flags) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

double fitted_coupling_rc_s(const VectorXd& raw, const VectorXd& coupled, double dt_s) {
  const Index n = std::min(raw.size(), coupled.size());
  double num = 0.0, den = 0.0;
  for (Index k = 1; k < n; ++k) {
    num += coupled[k - 1] * (coupled[k] - (raw[k] - raw[k - 1]));
    den += coupled[k - 1] * coupled[k - 1];
  }
  const double a = den > 0.0 ? num / den : std::numeric_limits<double>::quiet_NaN();
  if (!(a > 0.0 && a < 1.0)) return std::numeric_limits<double>::quiet_NaN();
  return -dt_s / std::log(a);
}

QualityReport check_quality(const VectorXd& u, const VectorXd& y, double dt_s,
                            const QualityOptions& options) {
  if (u.size() != y.size()) {
    throw std::invalid_argument(
        fmt::format("quality: input has {} samples, output {}", u.size(), y.size()));
  }
  if (!(dt_s > 0.0)) throw std::invalid_argument("quality: dt_s must be > 0");
  signal::CorrelatorOptions opt = options.correlator;
  opt.dt_s = dt_s;
  if (u.size() < 4 * opt.lags) {
    throw std::invalid_argument(
        fmt::format("quality: {} samples are too few for a lag window of "
                    "{} (need at least {})",
                    u.size(), opt.lags, 4 * opt.lags));
  }
  QualityReport rep;
  check_sampling(dt_s, options, rep);
  check_clipping(u, "input", options, rep);
  check_clipping(y, "output", options, rep);
  check_coupled_pairs(dt_s, options, rep);
  const VectorXd uc = u.array() - u.mean();
  const VectorXd yc = y.array() - y.mean();
  const Correlations c = correlate(uc, yc, opt);
  if (c.ruu(0) > 0.0) check_excitation(c, options, rep);
  check_response(c, options, rep);
  return rep;
}

}  // namespace rig::ident
