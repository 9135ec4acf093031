#include "rig/diagnose/residual_stats.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <unsupported/Eigen/FFT>
#include <vector>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/locate.hpp"
#include "rig/model/transfer_function.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::diagnose {
namespace {

// Fewer samples than this carry no amplitude or direction test.
constexpr Eigen::Index kMinAmplitudeSamples = 64;

}  // namespace

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

namespace {

// Above this many lags the autocorrelations are taken by FFT (the coupling test's, over three
// of its time constants); below it directly, as the tests at the excitation's scale always were.
constexpr Eigen::Index kDirectLagsMax = 256;

// x's circular autocorrelation over a zero-padded length (no wrap for lags below n), lags
// 0..lags.
Eigen::VectorXd autocorrelation_fft(const Eigen::VectorXd& x, Eigen::Index lags) {
  std::size_t len = 1;
  while (len < static_cast<std::size_t>(x.size() + lags)) len *= 2;
  std::vector<double> padded(len, 0.0);
  std::copy(x.data(), x.data() + x.size(), padded.begin());
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, padded);
  for (auto& v : spectrum) v = std::norm(v);
  std::vector<double> back;
  fft.inv(back, spectrum);
  return Eigen::Map<const Eigen::VectorXd>(back.data(), lags + 1);
}

}  // namespace

double bartlett_factor(const Eigen::VectorXd& a, const Eigen::VectorXd& b, Eigen::Index lags) {
  const Eigen::Index n = a.size();
  const double aa = a.squaredNorm(), bb = b.squaredNorm();
  if (aa <= 0.0 || bb <= 0.0) return 1.0;
  double c = 1.0;
  if (lags = std::min(lags, n - 1); lags > kDirectLagsMax) {
    const Eigen::VectorXd ra = autocorrelation_fft(a, lags), rb = autocorrelation_fft(b, lags);
    for (Eigen::Index k = 1; k <= lags; ++k) c += 2.0 * (ra(k) / aa) * (rb(k) / bb);
    return std::max(c, 1.0);
  }
  for (Eigen::Index k = 1; k <= lags; ++k) {
    const double ra = a.head(n - k).dot(a.tail(n - k)) / aa;
    const double rb = b.head(n - k).dot(b.tail(n - k)) / bb;
    c += 2.0 * ra * rb;
  }
  return std::max(c, 1.0);
}

Ls least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& r) {
  Ls out;
  const Eigen::MatrixXd xtx = x.transpose() * x;
  out.inv = xtx.completeOrthogonalDecomposition().pseudoInverse();
  out.beta = out.inv * (x.transpose() * r);
  out.rss = (r - x * out.beta).squaredNorm();
  return out;
}

Eigen::VectorXd ar_whitener(const Eigen::VectorXd& e, int order) {
  const Eigen::Index n = e.size(), p = order;
  Eigen::VectorXd a = Eigen::VectorXd::Ones(1);
  if (p < 1 || n < 8 * p || !(e.squaredNorm() > 0.0)) return a;
  Eigen::MatrixXd x(n - p, p);
  for (Eigen::Index j = 0; j < p; ++j) x.col(j) = e.segment(p - 1 - j, n - p);
  const Ls fit = least_squares(x, e.tail(n - p));  // e(k) = sum_j phi_j e(k - j) + w(k)
  a.resize(p + 1);
  a(0) = 1.0;
  a.tail(p) = -fit.beta;
  return a;
}

Eigen::VectorXd whiten(const Eigen::VectorXd& x, const Eigen::VectorXd& a) {
  const Eigen::Index n = x.size(), p = a.size() - 1;
  if (n <= p) return Eigen::VectorXd();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(n - p);
  for (Eigen::Index j = 0; j <= p; ++j) w += a(j) * x.segment(p - j, n - p);
  return w;
}

GlsFit gls_fit(const Eigen::MatrixXd& x, const Eigen::VectorXd& r, const Eigen::VectorXd& reference,
               int order, Eigen::Index lags) {
  const Eigen::VectorXd a = ar_whitener(r - x * least_squares(x, r).beta, order);
  const Eigen::Index p = x.cols();
  Eigen::MatrixXd xw(r.size() - (a.size() - 1), p);
  for (Eigen::Index j = 0; j < p; ++j) xw.col(j) = whiten(x.col(j), a);
  const Eigen::VectorXd rw = whiten(r, a);
  GlsFit out{least_squares(xw, rw)};
  const Eigen::VectorXd ew = rw - xw * out.fit.beta;
  const double n_eff =
      static_cast<double>(rw.size()) / bartlett_factor(ew, whiten(reference, a), lags);
  out.s2 = out.fit.rss / std::max(1.0, n_eff - static_cast<double>(p));
  return out;
}

Eigen::VectorXd detrend(const Problem& pr, const Eigen::VectorXd& x) {
  return x - smooth_zero_phase(x, drift_smooth_s(pr), pr.dt_s);
}

Eigen::VectorXd masked_response(const Problem& pr, const Eigen::VectorXd& u) {
  Eigen::VectorXd z = model::simulate(pr.tf, u, pr.dt_s);
  if (pr.output_rc_s) z = signal::ac_couple(z, pr.dt_s, *pr.output_rc_s);
  return detrend(pr, z);
}

std::optional<Rows> rows_of(const Problem& pr, const Eigen::VectorXd& r_all,
                            const Eigen::VectorXd& yh_all, Eigen::Index from, Eigen::Index to) {
  const Eigen::Index n = r_all.size();
  while (from < n && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::Index m = (to < 0 ? n : std::min(to, n)) - from;
  if (m < kMinAmplitudeSamples) return std::nullopt;
  Rows rows{from, m, detrend(pr, r_all).segment(from, m), detrend(pr, yh_all).segment(from, m)};
  rows.c = bartlett_factor(rows.r, rows.yh, std::min<Eigen::Index>(200, m / 4));
  rows.n_eff = static_cast<double>(m) / rows.c;
  return rows;
}

}  // namespace rig::diagnose
