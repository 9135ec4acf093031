// The frequency response's 95 % band from the asymptotic covariance (frf_uncertainty.hpp)
// against seeded Monte Carlo runs of the estimator it describes: MMFM refined by the
// time-domain output error on a second order plus dead time like the
// Stornoway set, Gaussian excitation, white plus low-frequency coloured output noise.
// The estimate is MMFM refined by the time-domain output error (output_error.hpp).
#include "rig/ident/frf_uncertainty.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "rig/ident/mmfm.hpp"
#include "rig/ident/output_error.hpp"
#include "rig/signal/correlators.hpp"
#include "rig/signal/excitation.hpp"
#include "rig/signal/random.hpp"

namespace rig::ident {
namespace {

constexpr double kDt = 0.01;
constexpr double kPi = 3.14159265358979323846;

model::TransferFunction sopdt() {
  const double wn = 2.0 * kPi * 2.03, zeta = 0.10, gain = 46.0;
  model::TransferFunction tf;
  tf.num = Eigen::VectorXd::Constant(1, gain * wn * wn);
  tf.den = Eigen::Vector3d(1.0, 2.0 * zeta * wn, wn * wn);
  tf.delay_s = 0.078;
  return tf;
}

signal::CorrelatorOptions window(Eigen::Index lags, Eigen::Index zero) {
  signal::CorrelatorOptions o;
  o.lags = lags;
  o.zero_index = zero;
  o.dt_s = kDt;
  return o;
}

struct McRun {
  model::TransferFunction model;
  std::vector<FrfUncertainty> band;
};

// One record: excitation, exact response, white noise of std white_kw plus AR(1) noise of
// std coloured_kw (pole 0.98: a 0.3 Hz corner) in kW.
McRun one_run(std::uint64_t seed, Eigen::Index n, const std::vector<double>& freqs) {
  signal::GaussianOptions g;
  g.n = n;
  g.dt_s = kDt;
  g.bandwidth_hz = 4.0;
  g.sigma = 0.3;
  g.seed = seed;
  const Eigen::VectorXd u = signal::gaussian_excitation(g);
  Eigen::VectorXd y = model::simulate(sopdt(), u, kDt);
  signal::Xoshiro256 rng(seed * 7919 + 1);
  const double white_kw = 5.0, coloured_kw = 4.0, pole = 0.98;
  double ar = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    ar = pole * ar + std::sqrt(1.0 - pole * pole) * coloured_kw * rng.normal();
    y(i) += white_kw * rng.normal() + ar;
  }
  const auto w = window(256, 102);
  MmfmOptions o;
  o.order = {2, 0};
  McRun r;
  const model::TransferFunction start =
      estimate_mmfm(signal::auto_correlation(u, w), signal::cross_correlation(y, u, w), o).model;
  r.model = refine_output_error(u, y, kDt, start, true).model;
  const InputNoiseSpectra s = input_noise_spectra(u, y, kDt, r.model);
  const Eigen::MatrixXd cov = asymptotic_covariance(r.model, s, static_cast<double>(n), true);
  r.band = frf_uncertainty(r.model, cov, freqs, true);
  return r;
}

TEST(FrfUncertainty, GradientMatchesFiniteDifferences) {
  const model::TransferFunction tf = sopdt();
  const double f = 1.7, h = 1e-6;
  const Eigen::VectorXcd psi = response_gradient(tf, f, true);
  ASSERT_EQ(psi.size(), 4);
  // theta = [a1, a0, b0, Td] of the monic model.
  for (int i = 0; i < 4; ++i) {
    model::TransferFunction p = tf;
    if (i < 2) p.den(1 + i) += h * std::max(1.0, std::abs(tf.den(1 + i)));
    if (i == 2) p.num(0) += h * tf.num(0);
    if (i == 3) p.delay_s += h;
    const double step = i < 2    ? h * std::max(1.0, std::abs(tf.den(1 + i)))
                        : i == 2 ? h * tf.num(0)
                                 : h;
    const std::complex<double> fd = (p.response(f) - tf.response(f)) / step;
    EXPECT_NEAR(std::abs(fd - psi(i)) / std::abs(psi(i)), 0.0, 1e-4) << "parameter " << i;
  }
}

TEST(FrfUncertainty, WhiteNoiseOutputErrorGivesTheCramerRaoForm) {
  // Flat excitation and white noise: S = sigma^2 H, so P = sigma^2 H^-1 (L/N).
  InputNoiseSpectra s;
  s.dt_s = kDt;
  s.fft_length = 512;
  const int bins = 257;
  s.freq_hz = Eigen::VectorXd::LinSpaced(bins, 0.0, 50.0);
  s.phi_u = Eigen::VectorXd::Constant(bins, 0.09);
  s.phi_v = Eigen::VectorXd::Constant(bins, 25.0);
  const Eigen::MatrixXd p1 = asymptotic_covariance(sopdt(), s, 6000.0, true, 1.0);
  const Eigen::MatrixXd p2 = asymptotic_covariance(sopdt(), s, 6000.0, true, 2.0);
  EXPECT_LT((p1 - p2).norm() / p1.norm(), 1e-9);  // a flat weight is no weight
  const Eigen::MatrixXd p4 = asymptotic_covariance(sopdt(), s, 24000.0, true, 1.0);
  EXPECT_NEAR(p4(0, 0) / p1(0, 0), 0.25, 1e-12);  // 1/N
}

TEST(FrfUncertainty, BandMatchesMonteCarloSpreadAndCoversTheTruth) {
  const std::vector<double> freqs = {0.5, 1.0, 1.8, 2.2, 3.0, 5.0};
  constexpr int kRuns = 30;
  constexpr std::uint64_t kSeed = 20261123;
  std::printf("[ seed %llu, %d runs ]\n", static_cast<unsigned long long>(kSeed), kRuns);
  const model::TransferFunction truth = sopdt();
  std::vector<double> sum_db(freqs.size()), sum2_db(freqs.size()), pred_db(freqs.size());
  std::vector<double> sum2_deg(freqs.size()), pred_deg(freqs.size());
  int covered = 0, judged = 0;
  for (int run = 0; run < kRuns; ++run) {
    const McRun r = one_run(kSeed + static_cast<std::uint64_t>(run), 6000, freqs);
    for (std::size_t i = 0; i < freqs.size(); ++i) {
      const std::complex<double> gt = truth.response(freqs[i]);
      const double e_db = r.band[i].mag_db - 20.0 * std::log10(std::abs(gt));
      const double e_deg = std::remainder(r.band[i].phase_deg - 180.0 / kPi * std::arg(gt), 360.0);
      sum_db[i] += e_db;
      sum2_db[i] += e_db * e_db;
      sum2_deg[i] += e_deg * e_deg;
      pred_db[i] += r.band[i].sd_db / kRuns;
      pred_deg[i] += r.band[i].sd_deg / kRuns;
      ++judged;
      if (std::abs(e_db) <= 1.96 * r.band[i].sd_db && std::abs(e_deg) <= 1.96 * r.band[i].sd_deg) {
        ++covered;
      }
    }
  }
  for (std::size_t i = 0; i < freqs.size(); ++i) {
    const double rms_db = std::sqrt(sum2_db[i] / kRuns), rms_deg = std::sqrt(sum2_deg[i] / kRuns);
    std::printf("f %.1f Hz: rms error %.3f dB %.2f deg, predicted sd %.3f dB %.2f deg\n", freqs[i],
                rms_db, rms_deg, pred_db[i], pred_deg[i]);
    // The asymptotic band describes the spread within a factor of 1.4 either way (measured:
    // 0.96-1.18).
    EXPECT_GT(pred_db[i], rms_db / 1.4) << freqs[i] << " Hz";
    EXPECT_LT(pred_db[i], rms_db * 1.4) << freqs[i] << " Hz";
    EXPECT_GT(pred_deg[i], rms_deg / 1.4) << freqs[i] << " Hz";
    EXPECT_LT(pred_deg[i], rms_deg * 1.4) << freqs[i] << " Hz";
  }
  const double coverage = static_cast<double>(covered) / judged;
  std::printf("joint coverage of the 95 %% bands: %.3f\n", coverage);
  EXPECT_GE(coverage, 0.85);
}

}  // namespace
}  // namespace rig::ident
