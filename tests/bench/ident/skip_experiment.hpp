// Seeded reproduction of thesis Table 5-1 (Fell's skip algorithm with relay correlation on a
// second-order analogue system of about 2 Hz, no dead time), shared by bench_ident_skip and
// the unit test.
//
// Plant: H(s) = K wn^2 / (s^2 + 2 zeta wn s + wn^2), fn = 2 Hz, zeta = 0.1, K = 1, no delay
// (thesis 5-2: "it was not possible to simulate the time delay"). Gaussian excitation of
// bandwidth f_max = 5 Hz (the thesis' frequency range of interest, 0.5-5 Hz), white output
// noise at SNR 10 dB. Sampled at fs = 200 Hz so that the slow rate fs/skip stays >= 2 f_max = 10 Hz
// up to skip 16 (12.5 Hz) and falls below it at skip 32 (6.25 Hz), as the thesis found.
//
// Each block is correlated on its own (the thesis downloaded 2048-sample blocks and formed
// 1600 products per lag at skip 1), with relay correlation and the given skip, and the block
// correlations are averaged (thesis: an average of twenty).
//
// Why the skip costs little while fs/skip >= 2 f_max, and why it breaks below. Without
// skip, r_yu(k) = 1/N sum_t y_t sgn(u_{t-k}) with y_t = sum_j h_j u_{t-j} gives
// r_yu(k) = sum_j h_j [1/N sum_t u_{t-j} sgn(u_{t-k})], and the bracket equals r_uu(k-j)
// on the anchor set shifted by j: up to edge terms the same sum, so r_yu = h * r_uu holds
// for the finite-record estimates themselves. With skip s the anchors form a grid of spacing
// s dt, and a grid shifted by j (not a multiple of s) picks different products. By Poisson
// summation a grid sum of a signal equals its integral, whatever the grid offset, when the
// signal has no content at or above the grid rate fs/s. The products u_{t-j} sgn(u_{t-k})
// of signals band-limited to f_max are band-limited to about 2 f_max (sgn adds a weak tail),
// so the identity (and the accuracy) survives while fs/s >= 2 f_max and breaks down below
// (measured: the break moves to skip 16 at fs = 100 Hz and past 32 at fs = 400 Hz). White
// output noise adds a part that does rise with s from the start: its products are
// uncorrelated from sample to sample, so their mean's variance is proportional to 1/N' = s/N.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>

#include "rig/ident/mmfm.hpp"
#include "rig/signal/correlators.hpp"
#include "tests/bench/ident/ident_experiments.hpp"

namespace rig::ident::experiments {

struct SkipSetup {
  double fn_hz = 2.0, zeta = 0.1, gain = 1.0;
  double fs_hz = 200.0;
  double f_max_hz = 5.0;          // excitation bandwidth = highest frequency of interest
  double snr_db = 10.0;           // output noise: var(y0) / var(noise), dB
  Eigen::Index lags = 1024;       // two-sided window (5.12 s at 200 Hz)
  Eigen::Index zero_index = 307;  // 30 % into the window (thesis 5-1-1: best 30-60 %)
  Eigen::Index products = 1600;   // per lag per block at skip 1 (thesis: 1600)
  int blocks = 20;                // block correlations averaged (thesis: twenty)

  double dt_s() const { return 1.0 / fs_hz; }
  Eigen::Index block_samples() const { return products + lags - 1; }
};

inline model::TransferFunction skip_plant_tf(const SkipSetup& s) {
  const double wn = 2.0 * M_PI * s.fn_hz;
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, s.gain * wn * wn);
  tf.den = Eigen::Vector3d(1.0, 2.0 * s.zeta * wn, wn * wn);
  return tf;
}

// One continuous run of blocks * block_samples samples (the analogue plant runs on between
// downloads, so every block starts in steady state).
inline Record skip_record(const SkipSetup& s, std::uint64_t seed) {
  signal::GaussianOptions g;
  g.dt_s = s.dt_s();
  g.n = s.block_samples() * s.blocks;
  g.bandwidth_hz = s.f_max_hz;
  g.seed = seed;
  return with_noise(skip_plant_tf(s), signal::gaussian_excitation(g), g.dt_s, s.snr_db, seed);
}

// Relay auto- and cross-correlation with Fell's skip, each block on its own, then averaged.
inline std::pair<signal::Correlation, signal::Correlation> skip_correlations(const Record& rec,
                                                                             const SkipSetup& s,
                                                                             int skip) {
  signal::CorrelatorOptions o;
  o.lags = s.lags;
  o.zero_index = s.zero_index;
  o.skip = skip;
  o.kind = signal::CorrelatorKind::kRelay;
  o.dt_s = s.dt_s();
  const Eigen::Index n = s.block_samples();
  signal::Correlation ruu, ryu;
  for (int b = 0; b < s.blocks; ++b) {
    const Eigen::VectorXd u = rec.u.segment(b * n, n), y = rec.y.segment(b * n, n);
    const signal::Correlation au = signal::auto_correlation(u, o);
    const signal::Correlation cy = signal::cross_correlation(y, u, o);
    if (b == 0) {
      ruu = au, ryu = cy;
    } else {
      ruu.r += au.r, ryu.r += cy.r;
    }
  }
  ruu.r /= s.blocks, ryu.r /= s.blocks;
  return {ruu, ryu};
}

// Plain MMFM (Hermite functions, automatic time scale), second order, no numerator zeros,
// dead time known to be zero.
inline MmfmResult skip_estimate(const signal::Correlation& ruu, const signal::Correlation& ryu) {
  MmfmOptions opt;
  opt.order = {2, 0};
  opt.delay_s = 0.0;
  return estimate_mmfm(ruu, ryu, opt);
}

}  // namespace rig::ident::experiments
