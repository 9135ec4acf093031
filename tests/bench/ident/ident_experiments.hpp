// Seeded experiments shared by the identification benchmarks and tests: the Stornoway-like
// diesel/alternator loop and the Rao-Garnier fourth-order benchmark.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "rig/model/transfer_function.hpp"
#include "rig/signal/excitation.hpp"
#include "rig/signal/random.hpp"

namespace rig::ident::experiments {

struct Record {
  Eigen::VectorXd u, y, y0;  // input, noisy output, noise-free output
  double noise_variance = 0.0;
  double dt_s = 0.01;
};

// H(s) = e^{-0.06 s} / (0.07 s^2 + 0.19 s + 11.05) (MMFM.md section 1).
inline model::TransferFunction stornoway_tf() {
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Ones(1);
  tf.den = Eigen::Vector3d(0.07, 0.19, 11.05);
  tf.delay_s = 0.06;
  return tf;
}

// (-6400 s + 1600) / (s^4 + 5 s^3 + 408 s^2 + 416 s + 1600).
inline model::TransferFunction rao_garnier_tf() {
  model::TransferFunction tf;
  tf.num = Eigen::Vector2d(-6400.0, 1600.0);
  tf.den.resize(5);
  tf.den << 1.0, 5.0, 408.0, 416.0, 1600.0;
  return tf;
}

// Adds white Gaussian noise of variance var(y0) / 10^(snr_db / 10).
inline Record with_noise(const model::TransferFunction& tf, Eigen::VectorXd u, double dt_s,
                         double snr_db, std::uint64_t seed) {
  Record r;
  r.dt_s = dt_s;
  r.u = std::move(u);
  r.y0 = simulate(tf, r.u, dt_s);
  const double var0 = (r.y0.array() - r.y0.mean()).square().mean();
  r.noise_variance = var0 / std::pow(10.0, snr_db / 10.0);
  signal::Xoshiro256 rng(seed ^ 0x5eedf00dULL);
  r.y = r.y0;
  const double sd = std::sqrt(r.noise_variance);
  for (Eigen::Index i = 0; i < r.y.size(); ++i) r.y(i) += sd * rng.normal();
  return r;
}

// Gaussian excitation of 4 Hz bandwidth at 100 Hz, output SNR 0 dB by default.
inline Record stornoway_record(std::uint64_t seed, double minutes, double snr_db = 0.0) {
  signal::GaussianOptions g;
  g.dt_s = 0.01;
  g.n = static_cast<Eigen::Index>(minutes * 60.0 / g.dt_s);
  g.bandwidth_hz = 4.0;
  g.seed = seed;
  return with_noise(stornoway_tf(), signal::gaussian_excitation(g), g.dt_s, snr_db, seed);
}

// PRBS (11-bit register, each bit held 3 samples) at Ts = 0.01 s, SNR 10 dB by default.
inline Record rao_garnier_record(std::uint64_t seed, Eigen::Index samples, double snr_db = 10.0) {
  signal::PrbsOptions p;
  p.n = samples;
  p.register_length = 11;
  p.clock_divider = 3;
  p.seed = seed;
  return with_noise(rao_garnier_tf(), signal::prbs_excitation(p), 0.01, snr_db, seed);
}

struct Stats {
  double mean = 0.0, std = 0.0;
};
inline Stats stats_of(const std::vector<double>& v) {
  Stats s;
  if (v.empty()) return s;
  for (double x : v) s.mean += x / static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.std = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
  return s;
}

}  // namespace rig::ident::experiments
