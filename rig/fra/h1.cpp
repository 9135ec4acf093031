#include "rig/fra/h1.hpp"

#include <fftw3.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rig::fra {
namespace {

// One FFTW real-to-complex plan and its buffers, freed on scope exit.
class RealFft {
 public:
  explicit RealFft(Eigen::Index n)
      : n_(n),
        in_(fftw_alloc_real(static_cast<std::size_t>(n))),
        out_(fftw_alloc_complex(static_cast<std::size_t>(n / 2 + 1))),
        plan_(fftw_plan_dft_r2c_1d(static_cast<int>(n), in_, out_, FFTW_ESTIMATE)) {
    if (plan_ == nullptr) throw std::runtime_error("h1: FFTW could not plan a transform");
  }
  ~RealFft() {
    fftw_destroy_plan(plan_);
    fftw_free(out_);
    fftw_free(in_);
  }
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  // Spectrum of window .* (x - mean(x)).
  Eigen::VectorXcd transform(const Eigen::Ref<const Eigen::VectorXd>& x,
                             const Eigen::VectorXd& window) {
    const double mean = x.mean();
    for (Eigen::Index i = 0; i < n_; ++i) in_[i] = window(i) * (x(i) - mean);
    fftw_execute(plan_);
    Eigen::VectorXcd s(n_ / 2 + 1);
    for (Eigen::Index k = 0; k < s.size(); ++k) s(k) = {out_[k][0], out_[k][1]};
    return s;
  }

 private:
  Eigen::Index n_;
  double* in_;
  fftw_complex* out_;
  fftw_plan plan_;
};

Eigen::VectorXd hann(Eigen::Index n) {
  Eigen::VectorXd w(n);
  // Periodic Hann, the form that sums to a constant at 50 % overlap.
  for (Eigen::Index i = 0; i < n; ++i) {
    w(i) = 0.5 -
           0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n));
  }
  return w;
}

}  // namespace

CrossSpectra welch_cross_spectra(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double dt_s,
                                 const WelchOptions& o) {
  const Eigen::Index l = o.segment_length;
  if (u.size() != y.size()) {
    throw std::invalid_argument("h1: u and y differ in length (" + std::to_string(u.size()) +
                                " vs " + std::to_string(y.size()) + ")");
  }
  if (l < 8) throw std::invalid_argument("h1: segment_length must be >= 8");
  if (!(o.overlap >= 0.0 && o.overlap <= 0.9)) {
    throw std::invalid_argument("h1: overlap must be in [0, 0.9]");
  }
  if (u.size() < l) {
    throw std::invalid_argument("h1: record of " + std::to_string(u.size()) +
                                " samples is shorter than one segment (" + std::to_string(l) + ")");
  }
  if (!(dt_s > 0.0)) throw std::invalid_argument("h1: dt_s must be > 0");
  const auto hop =
      std::max<Eigen::Index>(1, std::llround(static_cast<double>(l) * (1 - o.overlap)));
  const Eigen::VectorXd window = hann(l);
  RealFft fft(l);
  CrossSpectra s;
  const Eigen::Index bins = l / 2 + 1;
  s.guu = Eigen::VectorXd::Zero(bins);
  s.gyy = Eigen::VectorXd::Zero(bins);
  s.gyu = Eigen::VectorXcd::Zero(bins);
  for (Eigen::Index start = 0; start + l <= u.size(); start += hop) {
    const Eigen::VectorXcd us = fft.transform(u.segment(start, l), window);
    const Eigen::VectorXcd ys = fft.transform(y.segment(start, l), window);
    s.guu += us.cwiseAbs2();
    s.gyy += ys.cwiseAbs2();
    s.gyu += (us.conjugate().array() * ys.array()).matrix();
    ++s.segments;
  }
  s.freq_hz = Eigen::VectorXd::LinSpaced(bins, 0.0, static_cast<double>(bins - 1)) /
              (static_cast<double>(l) * dt_s);
  return s;
}

std::vector<model::FrfPoint> h1_estimate(const Eigen::VectorXd& u, const Eigen::VectorXd& y,
                                         double dt_s, const WelchOptions& o) {
  const CrossSpectra s = welch_cross_spectra(u, y, dt_s, o);
  std::vector<model::FrfPoint> out;
  for (Eigen::Index k = 1; k < s.freq_hz.size(); ++k) {
    const double f = s.freq_hz(k);
    if (f < o.f_min_hz || f > o.f_max_hz || !(s.guu(k) > 0.0)) continue;
    const std::complex<double> h = s.gyu(k) / s.guu(k);
    model::FrfPoint p;
    p.freq_hz = f;
    p.mag = std::abs(h);
    p.phase_deg = model::wrap_deg(std::arg(h) * 180.0 / std::numbers::pi);
    p.coherence = s.gyy(k) > 0.0 ? std::norm(s.gyu(k)) / (s.guu(k) * s.gyy(k)) : 0.0;
    const double gamma2 = std::max(p.coherence, 1e-12);
    const double eps = std::sqrt((1.0 - gamma2) / (2.0 * gamma2 * s.segments));
    p.mag_lo = p.mag * std::max(0.0, 1.0 - eps);
    p.mag_hi = p.mag * (1.0 + eps);
    out.push_back(p);
  }
  return out;
}

}  // namespace rig::fra
