#include "rig/ident/frf_uncertainty.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

#include "rig/signal/correlators.hpp"
#include "rig/signal/random.hpp"

namespace rig::ident {
namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kDbPerNeper = 20.0 / std::numbers::ln10;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kZ95 = 1.959963984540054;
constexpr std::uint64_t kSimultaneousSeed = 95;
// The noise spectrum is floored at this share of its peak: a bin with no residual at all
// would otherwise claim an infinitely precise response.
constexpr double kMinNoiseShare = 1e-4;
// Bins where the excitation has less than this share of its peak density carry no
// information and are left out (their Phi_v / Phi_u is only rounding).
constexpr double kMinInputShare = 1e-9;

// Parzen lag window on |tau| <= m: PSD-preserving, so the smoothed spectra stay >= 0.
double parzen(double tau, double m) {
  const double x = std::abs(tau) / m;
  if (x <= 0.5) return 1.0 - 6.0 * x * x + 6.0 * x * x * x;
  if (x <= 1.0) return 2.0 * std::pow(1.0 - x, 3);
  return 0.0;
}

// Sum over |tau| <= m of w(tau) r(tau) e^{-j w tau} at bin k of an L-point grid (an FFT of
// the windowed lags placed circularly; lags beyond L/2 alias, which the callers avoid with
// L > 2 m).
Eigen::VectorXcd smoothed_spectrum(const signal::Correlation& r, Eigen::Index m, int fft_length) {
  std::vector<double> x(static_cast<std::size_t>(fft_length), 0.0);
  for (Eigen::Index tau = -m; tau <= m; ++tau) {
    const double v =
        parzen(static_cast<double>(tau), static_cast<double>(m) + 1.0) * r.r(r.zero_index + tau);
    x[static_cast<std::size_t>((tau % fft_length + fft_length) % fft_length)] += v;
  }
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, x);
  const int bins = fft_length / 2 + 1;
  Eigen::VectorXcd out(bins);
  for (int k = 0; k < bins; ++k) out(k) = spectrum[static_cast<std::size_t>(k)];
  return out;
}

int parameter_count(const model::TransferFunction& m, bool delay_estimated) {
  return m.order() + static_cast<int>(m.num.size()) + (delay_estimated ? 1 : 0);
}

}  // namespace

InputNoiseSpectra input_noise_spectra(const Eigen::VectorXd& u, const Eigen::VectorXd& y,
                                      double dt_s, const model::TransferFunction& model,
                                      int half_width, int fft_length) {
  if (u.size() != y.size() || u.size() < 4 * half_width || half_width < 8 ||
      fft_length < 2 * half_width || !(dt_s > 0.0)) {
    throw std::invalid_argument(
        "input_noise_spectra: need equal lengths of at least 4 half-widths, half_width >= 8, "
        "fft_length >= 2 half_width, dt_s > 0");
  }
  signal::CorrelatorOptions w;
  w.lags = 2 * half_width + 1;
  w.zero_index = half_width;
  w.dt_s = dt_s;
  w.kind = signal::CorrelatorKind::kFft;
  const Eigen::VectorXd v = y - model::simulate(model, u, dt_s);
  const Eigen::VectorXcd suu =
      smoothed_spectrum(signal::auto_correlation(u, w), half_width, fft_length);
  const Eigen::VectorXcd svv =
      smoothed_spectrum(signal::auto_correlation(v, w), half_width, fft_length);
  InputNoiseSpectra s;
  s.dt_s = dt_s;
  s.fft_length = fft_length;
  const Eigen::Index bins = suu.size();
  s.freq_hz.resize(bins);
  s.phi_u = suu.real().cwiseMax(0.0);
  s.phi_v = svv.real().cwiseMax(kMinNoiseShare * svv.real().cwiseAbs().maxCoeff());
  for (Eigen::Index k = 0; k < bins; ++k) {
    s.freq_hz(k) = static_cast<double>(k) / (fft_length * dt_s);
  }
  return s;
}

Eigen::VectorXcd response_gradient(const model::TransferFunction& model, double freq_hz,
                                   bool delay_estimated) {
  const model::TransferFunction tf = model::monic(model);
  const int n = tf.order();
  const int nb = static_cast<int>(tf.num.size());
  const cd s(0.0, kTwoPi * freq_hz);
  cd a = 0.0, b = 0.0;
  for (Eigen::Index i = 0; i < tf.den.size(); ++i) a = a * s + tf.den(i);
  for (Eigen::Index i = 0; i < tf.num.size(); ++i) b = b * s + tf.num(i);
  const cd delay = std::exp(-s * tf.delay_s);
  const cd g = b / a * delay;
  Eigen::VectorXcd psi(parameter_count(tf, delay_estimated));
  for (int i = 0; i < n; ++i) psi(i) = -g * std::pow(s, n - 1 - i) / a;  // a_{n-1} .. a_0
  for (int j = 0; j < nb; ++j) psi(n + j) = std::pow(s, nb - 1 - j) * delay / a;
  if (delay_estimated) psi(n + nb) = -s * g;
  return psi;
}

Eigen::MatrixXd asymptotic_covariance(const model::TransferFunction& model,
                                      const InputNoiseSpectra& spectra, double samples,
                                      bool delay_estimated, double weight_power) {
  if (!model.is_proper()) throw std::invalid_argument("asymptotic_covariance: improper model");
  if (!(samples > 0.0)) throw std::invalid_argument("asymptotic_covariance: samples must be > 0");
  const int p = parameter_count(model, delay_estimated);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(p, p), s = Eigen::MatrixXd::Zero(p, p);
  const double peak_u = spectra.phi_u.maxCoeff();
  const Eigen::Index bins = spectra.freq_hz.size();
  for (Eigen::Index k = 0; k < bins; ++k) {
    const double pu = spectra.phi_u(k);
    if (!(pu > kMinInputShare * peak_u)) continue;
    // Bins 1 .. L/2-1 stand for themselves and their mirror image at -f.
    const double mult = (k == 0 || k == bins - 1) ? 1.0 : 2.0;
    const Eigen::VectorXcd psi = response_gradient(model, spectra.freq_hz(k), delay_estimated);
    const Eigen::MatrixXd outer = (psi * psi.adjoint()).real();
    const double w = std::pow(pu / peak_u, weight_power);  // scale cancels in the sandwich
    h += mult * w * outer;
    s += mult * w * w * (spectra.phi_v(k) / pu) * outer;
  }
  // Equilibrated (unit diagonal) before the inverse: the coefficients of a model span many
  // orders of magnitude (a0 ~ 1e4 against a delay ~ 1e-2).
  const Eigen::VectorXd d = h.diagonal().cwiseMax(0.0).cwiseSqrt().cwiseInverse();
  const auto inf = Eigen::MatrixXd::Constant(p, p, std::numeric_limits<double>::infinity());
  if (!d.allFinite()) return inf;
  const Eigen::MatrixXd hs = d.asDiagonal() * h * d.asDiagonal();
  const Eigen::MatrixXd ss = d.asDiagonal() * s * d.asDiagonal();
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(hs);
  if (!lu.isInvertible()) return inf;
  const Eigen::MatrixXd hi = lu.inverse();
  // avg_w = (1/L) sum over the full circle: P = (1/N) (H/L)^-1 (S/L) (H/L)^-1.
  const Eigen::MatrixXd cov = static_cast<double>(spectra.fft_length) / samples * d.asDiagonal() *
                              (hi * ss * hi) * d.asDiagonal();
  return cov.allFinite() ? cov : inf;
}

std::vector<FrfUncertainty> frf_uncertainty(const model::TransferFunction& model,
                                            const Eigen::MatrixXd& cov,
                                            const std::vector<double>& freqs_hz,
                                            bool delay_estimated) {
  std::vector<FrfUncertainty> out;
  out.reserve(freqs_hz.size());
  for (double f : freqs_hz) {
    const cd g = model.response(f);
    const Eigen::VectorXcd rel = response_gradient(model, f, delay_estimated) / g;
    const Eigen::VectorXd j_db = kDbPerNeper * rel.real();
    const Eigen::VectorXd j_deg = kDegPerRad * rel.imag();
    FrfUncertainty u;
    u.freq_hz = f;
    u.mag_db = 20.0 * std::log10(std::abs(g));
    u.phase_deg = kDegPerRad * std::arg(g);
    // A NaN variance (a covariance of infinities) is an unknown band, never a zero one.
    const double v_db = j_db.dot(cov * j_db), v_deg = j_deg.dot(cov * j_deg);
    const double inf = std::numeric_limits<double>::infinity();
    u.sd_db = std::isnan(v_db) ? inf : std::sqrt(std::max(0.0, v_db));
    u.sd_deg = std::isnan(v_deg) ? inf : std::sqrt(std::max(0.0, v_deg));
    out.push_back(u);
  }
  return out;
}

double simultaneous_factor95(const model::TransferFunction& model, const Eigen::MatrixXd& cov,
                             const std::vector<double>& freqs_hz, bool delay_estimated) {
  const double inf = std::numeric_limits<double>::infinity();
  if (!cov.allFinite() || freqs_hz.empty()) return inf;
  // theta = L z with L L^T = cov (eigen-decomposition: cov may be semi-definite).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  const Eigen::MatrixXd l =
      eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  const auto n = static_cast<Eigen::Index>(freqs_hz.size());
  Eigen::MatrixXd j(2 * n, cov.rows());  // rows: dB then deg per frequency, in sd units
  for (Eigen::Index i = 0; i < n; ++i) {
    const double f = freqs_hz[static_cast<std::size_t>(i)];
    const Eigen::VectorXcd rel = response_gradient(model, f, delay_estimated) / model.response(f);
    const Eigen::VectorXd jd = rel.real(), jp = rel.imag();
    const double sd_d = std::sqrt(jd.dot(cov * jd)), sd_p = std::sqrt(jp.dot(cov * jp));
    j.row(i) =
        (sd_d > 0.0 ? Eigen::VectorXd(jd / sd_d) : Eigen::VectorXd::Zero(jd.size())).transpose();
    j.row(n + i) =
        (sd_p > 0.0 ? Eigen::VectorXd(jp / sd_p) : Eigen::VectorXd::Zero(jp.size())).transpose();
  }
  const Eigen::MatrixXd jl = j * l;
  signal::Xoshiro256 rng(kSimultaneousSeed);
  std::vector<double> worst(kSimultaneousDraws);
  Eigen::VectorXd z(cov.rows());
  for (double& w : worst) {
    for (Eigen::Index k = 0; k < z.size(); ++k) z(k) = rng.normal();
    w = (jl * z).cwiseAbs().maxCoeff();
  }
  const auto q = worst.begin() + static_cast<std::ptrdiff_t>(0.95 * kSimultaneousDraws);
  std::nth_element(worst.begin(), q, worst.end());
  return std::max(*q, kZ95);
}

BandWidth95 worst_band95(const std::vector<FrfUncertainty>& points, double factor) {
  BandWidth95 w;
  for (const auto& p : points) {
    w.db = std::max(w.db, factor * p.sd_db);
    w.deg = std::max(w.deg, factor * p.sd_deg);
  }
  if (points.empty()) w.db = w.deg = std::numeric_limits<double>::infinity();
  return w;
}

std::vector<double> log_frequencies_hz(double f0_hz, double f1_hz, int n) {
  if (!(f0_hz > 0.0) || !(f1_hz > f0_hz) || n < 2) {
    throw std::invalid_argument("log_frequencies_hz: need 0 < f0 < f1 and n >= 2");
  }
  std::vector<double> f(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    f[static_cast<std::size_t>(i)] =
        f0_hz * std::pow(f1_hz / f0_hz, static_cast<double>(i) / (n - 1));
  }
  return f;
}

}  // namespace rig::ident
