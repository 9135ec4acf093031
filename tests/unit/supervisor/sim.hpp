// A small plant and excitation for the supervisor tests: the bias-to-power response of a
// generator set as a second-order system with dead time at 100 Hz,
//   G(s) = K wn^2 e^{-s Td} / (s^2 + 2 zeta wn s + wn^2),  zeta 0.1 -> resonance gain 5,
// discretised exactly for a zero-order-hold input, plus white measurement noise; and a
// Gaussian excitation low-pass filtered (2nd-order Butterworth, bilinear) to about twice the
// resonance, scaled to unit rms and clipped at 3 sigma (MMFM.md section 8).
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <deque>
#include <numbers>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>

#include "drivers/governor_link.hpp"

namespace rig::session::testing {

struct PlantParams {
  double gain_kw_per_pct = 46.0;  // 1 % of a 4.6 MW set
  double fn_hz = 2.0;
  double zeta = 0.1;
  double delay_s = 0.06;
  double p0_kw = 3500.0;
  double noise_rms_kw = 1.0;
  double dt_s = 0.01;

  double magnitude(double f_hz) const {
    const double wn = 2 * std::numbers::pi * fn_hz, w = 2 * std::numbers::pi * f_hz;
    return gain_kw_per_pct * wn * wn /
           std::abs(std::complex<double>(wn * wn - w * w, 2 * zeta * wn * w));
  }
};

class SimPlant {
 public:
  SimPlant(const PlantParams& p, unsigned seed) : p_(p), rng_(seed), noise_(0.0, p.noise_rms_kw) {
    const double wn = 2 * std::numbers::pi * p.fn_hz;
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    m << 0, 1, 0, -wn * wn, -2 * p.zeta * wn, 1, 0, 0, 0;
    const Eigen::Matrix3d e = (m * p.dt_s).exp();
    ad_ = e.topLeftCorner<2, 2>();
    bd_ = e.block<2, 1>(0, 2);
    c_ = p.gain_kw_per_pct * wn * wn;
    delay_.assign(static_cast<std::size_t>(std::llround(p.delay_s / p.dt_s)), 0.0);
    sample_.power_kw = p.p0_kw;
    sample_.status = drivers::kRunning | drivers::kBreakerClosed;
  }
  // Applies the bias for one tick and returns the next sample.
  const drivers::Sample& step(double bias_pct) {
    delay_.push_back(bias_pct);
    const double v = delay_.front();
    delay_.pop_front();
    x_ = ad_ * x_ + bd_ * v;
    response_kw_ = c_ * x_(0);
    sample_.power_kw = p_.p0_kw + response_kw_ + noise_(rng_);
    sample_.plant_time_s += p_.dt_s;
    ++sample_.counter;
    return sample_;
  }
  const drivers::Sample& sample() const { return sample_; }
  double response_kw() const { return response_kw_; }  // noise-free deviation

 private:
  PlantParams p_;
  std::mt19937 rng_;
  std::normal_distribution<double> noise_;
  Eigen::Matrix2d ad_;
  Eigen::Vector2d bd_;
  double c_ = 0.0;
  Eigen::Vector2d x_ = Eigen::Vector2d::Zero();
  std::deque<double> delay_;
  drivers::Sample sample_;
  double response_kw_ = 0.0;
};

// Unit-rms Gaussian noise, 2nd-order Butterworth low-pass at cutoff_hz, clipped at 3 sigma.
inline Eigen::VectorXd filtered_noise(Eigen::Index n, double dt_s, double cutoff_hz,
                                      unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> white(0.0, 1.0);
  // Bilinear transform with prewarping: K = tan(pi fc dt).
  const double k = std::tan(std::numbers::pi * cutoff_hz * dt_s);
  const double q = std::sqrt(2.0);
  const double norm = 1.0 / (1.0 + q * k + k * k);
  const double b0 = k * k * norm, b1 = 2 * b0, b2 = b0;
  const double a1 = 2 * (k * k - 1) * norm, a2 = (1 - q * k + k * k) * norm;
  Eigen::VectorXd y(n);
  double x1 = 0, x2 = 0, y1 = 0, y2 = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x0 = white(rng);
    const double y0 = b0 * x0 + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
    x2 = x1;
    x1 = x0;
    y2 = y1;
    y1 = y0;
    y(i) = y0;
  }
  const double rms = std::sqrt(y.squaredNorm() / static_cast<double>(n));
  return (y / rms).cwiseMax(-3.0).cwiseMin(3.0);
}

}  // namespace rig::session::testing
