// Monte Carlo comparisons: MMFM (identify) and SRIVC against the Cramer-Rao bound.
#include "tests/bench/ident/mc_cases.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "rig/ident/crlb.hpp"
#include "rig/ident/identify.hpp"
#include "rig/ident/srivc.hpp"
#include "tests/bench/ident/ident_experiments.hpp"

namespace rig::ident::bench {
namespace {

using experiments::stats_of;
using Clock = std::chrono::steady_clock;

struct Series {
  std::vector<double> fn, zeta, gain, td, fn_se, zeta_se, gain_se, td_se;
  double seconds = 0.0;
  int failures = 0;
  void add(const DerivedFigures& d, double td_s, double td_se_s) {
    fn.push_back(d.fn_hz), zeta.push_back(d.zeta), gain.push_back(d.gain);
    fn_se.push_back(d.fn_hz_std), zeta_se.push_back(d.zeta_std), gain_se.push_back(d.gain_std);
    td.push_back(td_s), td_se.push_back(td_se_s);
  }
};

void print_row(const char* name, double truth, double crlb_std, const std::vector<double>& m,
               const std::vector<double>& m_se, const std::vector<double>& s,
               const std::vector<double>& s_se, double scale, const char* unit) {
  const auto a = stats_of(m), b = stats_of(s);
  const double ea = crlb_std * crlb_std / (a.std * a.std), eb = crlb_std * crlb_std / (b.std * b.std);
  std::printf("  %-6s %9.5f | MMFM bias %7.3f%s std %7.3f%s se %7.3f%s | SRIVC bias %7.3f%s "
              "std %7.3f%s se %7.3f%s | CRLB %7.3f%s | eff %5.2f %5.2f\n",
              name, truth, (a.mean - truth) * scale, unit, a.std * scale, unit,
              stats_of(m_se).mean * scale, unit, (b.mean - truth) * scale, unit, b.std * scale,
              unit, stats_of(s_se).mean * scale, unit, crlb_std * scale, unit, ea, eb);
}

}  // namespace

void stornoway_mc(const McConfig& cfg) {
  const TransferFunction tf = experiments::stornoway_tf();
  const DerivedFigures truth = derived_figures(tf, Eigen::MatrixXd());
  std::printf("\n== Stornoway-like loop e^{-0.06s}/(0.07s^2+0.19s+11.05): Gaussian 4 Hz, "
              "100 Hz, SNR 0 dB, %.1f min, %d runs, seed %llu (run r: seed+r), lags %d ==\n",
              cfg.minutes, cfg.runs, static_cast<unsigned long long>(cfg.seed), cfg.lags);
  Series mm, sr;
  std::vector<double> crlb_fn, crlb_zeta, crlb_gain, crlb_td;
  for (int r = 0; r < cfg.runs; ++r) {
    const auto rec = experiments::stornoway_record(cfg.seed + r, cfg.minutes);
    IdentifyOptions io;
    io.order = ModelOrder{2, 0};
    io.correlator.lags = cfg.lags;
    auto t0 = Clock::now();
    try {
      const IdentifyResult res = identify(rec.u, rec.y, rec.dt_s, io);
      mm.add(res.derived, res.delay_s, res.delay_std_s);
    } catch (const std::exception& e) {
      ++mm.failures;
      std::printf("  run %d MMFM failed: %s\n", r, e.what());
    }
    auto t1 = Clock::now();
    SrivcOptions so;
    so.order = {2, 0};
    so.max_delay_s = 0.3;
    try {
      const SrivcResult res = estimate_srivc(rec.u.array() - rec.u.mean(),
                                             rec.y.array() - rec.y.mean(), rec.dt_s, so);
      sr.add(res.derived, res.delay_s, res.delay_std_s);
    } catch (const std::exception& e) {
      ++sr.failures;
      std::printf("  run %d SRIVC failed: %s\n", r, e.what());
    }
    auto t2 = Clock::now();
    mm.seconds += std::chrono::duration<double>(t1 - t0).count();
    sr.seconds += std::chrono::duration<double>(t2 - t1).count();
    const CramerRaoBound b = cramer_rao_bound(tf, rec.u, rec.dt_s, rec.noise_variance);
    crlb_fn.push_back(b.derived.fn_hz_std), crlb_zeta.push_back(b.derived.zeta_std);
    crlb_gain.push_back(b.derived.gain_std), crlb_td.push_back(b.std_dev(b.std_dev.size() - 1));
  }
  std::printf("  (bias and std in %% of truth, Td in ms; se = mean reported std error; "
              "eff = CRLB var / MC var)\n");
  print_row("fn_hz", truth.fn_hz, stats_of(crlb_fn).mean, mm.fn, mm.fn_se, sr.fn, sr.fn_se,
            100.0 / truth.fn_hz, "%");
  print_row("zeta", truth.zeta, stats_of(crlb_zeta).mean, mm.zeta, mm.zeta_se, sr.zeta,
            sr.zeta_se, 100.0 / truth.zeta, "%");
  print_row("gain", truth.gain, stats_of(crlb_gain).mean, mm.gain, mm.gain_se, sr.gain,
            sr.gain_se, 100.0 / truth.gain, "%");
  print_row("Td_s", tf.delay_s, stats_of(crlb_td).mean, mm.td, mm.td_se, sr.td, sr.td_se,
            1000.0, "ms");
  std::printf("  failures: MMFM %d, SRIVC %d; time per run: MMFM %.3f s, SRIVC %.3f s\n",
              mm.failures, sr.failures, mm.seconds / cfg.runs, sr.seconds / cfg.runs);
}

void rao_garnier_mc(const McConfig& cfg) {
  const TransferFunction tf = experiments::rao_garnier_tf();
  const Eigen::Index samples = 2 * 2047 * 3;
  std::printf("\n== Rao-Garnier (-6400s+1600)/(s^4+5s^3+408s^2+416s+1600): PRBS 11 bit x3, "
              "Ts 0.01 s, %lld samples, SNR 10 dB, %d runs, seed %llu (run r: seed+r), "
              "Td = 0 known ==\n",
              static_cast<long long>(samples), cfg.runs, static_cast<unsigned long long>(cfg.seed));
  const Eigen::VectorXd truth = pack_parameters(tf).tail(6);  // a3..a0, b1, b0
  const char* names[] = {"a3", "a2", "a1", "a0", "b1", "b0"};
  std::vector<std::vector<double>> mm(6), sr(6);
  Eigen::VectorXd crlb_var = Eigen::VectorXd::Zero(6);
  int mm_fail = 0, sr_fail = 0;
  for (int r = 0; r < cfg.runs; ++r) {
    const auto rec = experiments::rao_garnier_record(cfg.seed + r, samples);
    IdentifyOptions io;
    io.order = ModelOrder{4, 1};
    io.delay_s = 0.0;
    io.correlator.lags = 2048;
    io.correlator.zero_index = 400;
    io.blocks = 0;
    try {
      const Eigen::VectorXd th = pack_parameters(monic(identify(rec.u, rec.y, rec.dt_s, io).model));
      for (int i = 0; i < 6; ++i) mm[i].push_back(th(i + 1));
    } catch (const std::exception& e) {
      ++mm_fail;
      std::printf("  run %d MMFM failed: %s\n", r, e.what());
    }
    SrivcOptions so;
    so.order = {4, 1};
    so.delay_s = 0.0;
    try {
      const SrivcResult res = estimate_srivc(rec.u.array() - rec.u.mean(),
                                             rec.y.array() - rec.y.mean(), rec.dt_s, so);
      const Eigen::VectorXd th = pack_parameters(res.model);
      for (int i = 0; i < 6; ++i) sr[i].push_back(th(i + 1));
    } catch (const std::exception& e) {
      ++sr_fail;
      std::printf("  run %d SRIVC failed: %s\n", r, e.what());
    }
    const CramerRaoBound b = cramer_rao_bound(tf, rec.u, rec.dt_s, rec.noise_variance, true);
    crlb_var += b.covariance.diagonal().head(6) / cfg.runs;
  }
  std::printf("  %-4s %10s | %12s %12s | %12s %12s | %10s\n", "par", "true", "MMFM mean",
              "MMFM std", "SRIVC mean", "SRIVC std", "CRLB std");
  for (int i = 0; i < 6; ++i) {
    const auto a = stats_of(mm[i]), b = stats_of(sr[i]);
    std::printf("  %-4s %10.3f | %12.3f %12.3f | %12.3f %12.3f | %10.3f\n", names[i], truth(i),
                a.mean, a.std, b.mean, b.std, std::sqrt(crlb_var(i)));
  }
  std::printf("  (CRLB for Td known, mean over runs; failures MMFM %d, SRIVC %d)\n", mm_fail,
              sr_fail);
}

namespace {

void print_order_table(const char* title, const IdentifyResult& r) {
  std::printf(" %s: chosen %d/%d, validation fit %.2f %%, Td %.4f s\n", title, r.order.n,
              r.order.m, r.validation_fit_pct, r.delay_s);
  std::printf("   %-6s %10s %12s %10s %10s\n", "order", "est fit %", "valid fit %", "score",
              "Td (s)");
  for (const OrderScore& s : r.order_table)
    std::printf("   %d/%-4d %10.2f %12.2f %10.2f %10.4f\n", s.order.n, s.order.m, s.fit_pct,
                s.validation_fit_pct, s.score, s.delay_s);
}

}  // namespace

void order_tables(const McConfig& cfg) {
  std::printf("\n== Model-order selection (seed 001 style): estimate on the first half, "
              "validate on the second, score = validation fit - 0.1 %% per parameter; "
              "seed %llu ==\n", static_cast<unsigned long long>(cfg.seed));
  const auto st = experiments::stornoway_record(cfg.seed, cfg.minutes);
  IdentifyOptions io;
  io.correlator.lags = cfg.lags;
  io.blocks = 0;
  print_order_table("Stornoway, SNR 0 dB, MMFM", identify(st.u, st.y, st.dt_s, io));
  io.method = IdentMethod::kSrivc;
  io.max_delay_s = 0.3;
  print_order_table("Stornoway, SNR 0 dB, SRIVC", identify(st.u, st.y, st.dt_s, io));
  const auto rg = experiments::rao_garnier_record(cfg.seed, 2 * 2047 * 3);
  IdentifyOptions ir;
  ir.correlator.lags = 2048;
  ir.correlator.zero_index = 400;
  ir.blocks = 0;
  ir.delay_s = 0.0;
  print_order_table("Rao-Garnier, SNR 10 dB, MMFM (Td = 0 known)",
                    identify(rg.u, rg.y, rg.dt_s, ir));
  ir.method = IdentMethod::kSrivc;
  print_order_table("Rao-Garnier, SNR 10 dB, SRIVC (Td = 0 known)",
                    identify(rg.u, rg.y, rg.dt_s, ir));
}

}  // namespace rig::ident::bench
