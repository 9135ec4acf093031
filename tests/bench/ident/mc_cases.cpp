// Monte Carlo comparisons: MMFM (identify) and SRIVC against the Cramer-Rao bound.
#include "tests/bench/ident/mc_cases.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
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

void print_row(
    const char* name, double truth, double crlb_std,
    const std::vector<std::pair<const std::vector<double>*, const std::vector<double>*>>& cols,
    double scale, const char* unit) {
  std::printf("  %-6s %8.5f |", name, truth);
  for (const auto& [v, se] : cols) {
    const auto a = stats_of(*v);
    std::printf(" bias %7.3f std %6.3f se %6.3f eff %4.2f |", (a.mean - truth) * scale,
                a.std * scale, stats_of(*se).mean * scale, crlb_std * crlb_std / (a.std * a.std));
  }
  std::printf(" CRLB %6.3f %s\n", crlb_std * scale, unit);
}

void run_series(Series& s, const char* label, int r, const std::function<void(Series&)>& f) {
  const auto t0 = Clock::now();
  try {
    f(s);
  } catch (const std::exception& e) {
    ++s.failures;
    std::printf("  run %d %s failed: %s\n", r, label, e.what());
  }
  s.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

void stornoway_mc(const McConfig& cfg) {
  const model::TransferFunction tf = experiments::stornoway_tf();
  const DerivedFigures truth = derived_figures(tf, Eigen::MatrixXd());
  std::printf(
      "\n== Stornoway-like loop e^{-0.06s}/(0.07s^2+0.19s+11.05): Gaussian 4 Hz, "
      "100 Hz, SNR 0 dB, %.1f min, %d runs, seed %llu (run r: seed+r), lags %d ==\n",
      cfg.minutes, cfg.runs, static_cast<unsigned long long>(cfg.seed), cfg.lags);
  Series mm, oe, sr;
  std::vector<double> crlb_fn, crlb_zeta, crlb_gain, crlb_td;
  for (int r = 0; r < cfg.runs; ++r) {
    const auto rec = experiments::stornoway_record(cfg.seed + r, cfg.minutes);
    IdentifyOptions io;
    io.order = model::ModelOrder{2, 0};
    io.correlator.lags = cfg.lags;
    run_series(mm, "MMFM", r, [&](Series& s) {
      const IdentifyResult res = identify(rec.u, rec.y, rec.dt_s, io);
      s.add(res.derived, res.delay_s, res.delay_std_s);
    });
    run_series(oe, "MMFM+OE", r, [&](Series& s) {
      IdentifyOptions o2 = io;
      o2.mmfm.refine = true;
      const IdentifyResult res = identify(rec.u, rec.y, rec.dt_s, o2);
      s.add(res.derived, res.delay_s, res.delay_std_s);
    });
    run_series(sr, "SRIVC", r, [&](Series& s) {
      SrivcOptions so;
      so.order = {2, 0};
      so.max_delay_s = 0.3;
      const SrivcResult res =
          estimate_srivc(rec.u.array() - rec.u.mean(), rec.y.array() - rec.y.mean(), rec.dt_s, so);
      s.add(res.derived, res.delay_s, res.delay_std_s);
    });
    const CramerRaoBound b = cramer_rao_bound(tf, rec.u, rec.dt_s, rec.noise_variance);
    if (cfg.csv) {
      const auto seed = static_cast<unsigned long long>(cfg.seed + r);
      for (const auto& [name, s] : {std::pair<const char*, Series*>{"mmfm", &mm},
                                    {"mmfm_oe", &oe},
                                    {"srivc", &sr},
                                    {"crlb_std", nullptr}}) {
        if (s && s->fn.size() != static_cast<size_t>(r + 1 - s->failures)) continue;
        if (s)
          std::fprintf(cfg.csv, "stornoway,%d,%llu,%s,%.9g,%.9g,%.9g,%.9g\n", r, seed, name,
                       s->fn.back(), s->zeta.back(), s->gain.back(), s->td.back());
        else
          std::fprintf(cfg.csv, "stornoway,%d,%llu,%s,%.9g,%.9g,%.9g,%.9g\n", r, seed, name,
                       b.derived.fn_hz_std, b.derived.zeta_std, b.derived.gain_std,
                       b.std_dev(b.std_dev.size() - 1));
      }
      std::fflush(cfg.csv);
    }
    crlb_fn.push_back(b.derived.fn_hz_std), crlb_zeta.push_back(b.derived.zeta_std);
    crlb_gain.push_back(b.derived.gain_std), crlb_td.push_back(b.std_dev(b.std_dev.size() - 1));
  }
  std::printf(
      "  columns: MMFM | MMFM+OE (correlation-domain refinement) | SRIVC. bias, std, "
      "se (mean reported std error) in %% of truth (Td in ms); eff = CRLB var / MC var\n");
  print_row("fn_hz", truth.fn_hz, stats_of(crlb_fn).mean,
            {{&mm.fn, &mm.fn_se}, {&oe.fn, &oe.fn_se}, {&sr.fn, &sr.fn_se}}, 100.0 / truth.fn_hz,
            "%");
  print_row("zeta", truth.zeta, stats_of(crlb_zeta).mean,
            {{&mm.zeta, &mm.zeta_se}, {&oe.zeta, &oe.zeta_se}, {&sr.zeta, &sr.zeta_se}},
            100.0 / truth.zeta, "%");
  print_row("gain", truth.gain, stats_of(crlb_gain).mean,
            {{&mm.gain, &mm.gain_se}, {&oe.gain, &oe.gain_se}, {&sr.gain, &sr.gain_se}},
            100.0 / truth.gain, "%");
  print_row("Td_s", tf.delay_s, stats_of(crlb_td).mean,
            {{&mm.td, &mm.td_se}, {&oe.td, &oe.td_se}, {&sr.td, &sr.td_se}}, 1000.0, "ms");
  std::printf(
      "  failures: MMFM %d, MMFM+OE %d, SRIVC %d; time per run: MMFM %.3f s, "
      "MMFM+OE %.3f s, SRIVC %.3f s\n",
      mm.failures, oe.failures, sr.failures, mm.seconds / cfg.runs, oe.seconds / cfg.runs,
      sr.seconds / cfg.runs);
  std::fflush(stdout);
}

void rao_garnier_mc(const McConfig& cfg) {
  const model::TransferFunction tf = experiments::rao_garnier_tf();
  const Eigen::Index samples = 2 * 2047 * 3;
  std::printf(
      "\n== Rao-Garnier (-6400s+1600)/(s^4+5s^3+408s^2+416s+1600): PRBS 11 bit x3, "
      "Ts 0.01 s, %lld samples, SNR 10 dB, %d runs, seed %llu (run r: seed+r), "
      "Td = 0 known ==\n",
      static_cast<long long>(samples), cfg.runs, static_cast<unsigned long long>(cfg.seed));
  const Eigen::VectorXd truth = pack_parameters(tf).tail(6);  // a3..a0, b1, b0
  const char* names[] = {"a3", "a2", "a1", "a0", "b1", "b0"};
  std::vector<std::vector<double>> est[3];
  for (auto& e : est) e.resize(6);
  Eigen::VectorXd crlb_var = Eigen::VectorXd::Zero(6);
  int fails[3] = {0, 0, 0};
  auto keep = [&](int k, const model::TransferFunction& model) {
    const Eigen::VectorXd th = pack_parameters(model::monic(model));
    for (int i = 0; i < 6; ++i) est[k][i].push_back(th(i + 1));
  };
  for (int r = 0; r < cfg.runs; ++r) {
    const auto rec = experiments::rao_garnier_record(cfg.seed + r, samples);
    IdentifyOptions io;
    io.order = model::ModelOrder{4, 1};
    io.delay_s = 0.0;
    io.correlator.lags = 2048;
    io.correlator.zero_index = 400;
    io.blocks = 0;
    for (int k = 0; k < 2; ++k) {
      io.mmfm.refine = k == 1;
      try {
        keep(k, identify(rec.u, rec.y, rec.dt_s, io).model);
      } catch (const std::exception& e) {
        ++fails[k];
        std::printf("  run %d MMFM failed: %s\n", r, e.what());
      }
    }
    SrivcOptions so;
    so.order = {4, 1};
    so.delay_s = 0.0;
    try {
      keep(2,
           estimate_srivc(rec.u.array() - rec.u.mean(), rec.y.array() - rec.y.mean(), rec.dt_s, so)
               .model);
    } catch (const std::exception& e) {
      ++fails[2];
      std::printf("  run %d SRIVC failed: %s\n", r, e.what());
    }
    const CramerRaoBound b = cramer_rao_bound(tf, rec.u, rec.dt_s, rec.noise_variance, true);
    crlb_var += b.covariance.diagonal().head(6) / cfg.runs;
  }
  std::printf("  %-4s %9s | %10s %9s | %10s %9s | %10s %9s | %9s\n", "par", "true", "MMFM mean",
              "std", "+OE mean", "std", "SRIVC mean", "std", "CRLB std");
  for (int i = 0; i < 6; ++i) {
    std::printf("  %-4s %9.2f |", names[i], truth(i));
    for (auto& e : est) {
      const auto a = stats_of(e[i]);
      std::printf(" %10.2f %9.2f |", a.mean, a.std);
    }
    std::printf(" %9.2f\n", std::sqrt(crlb_var(i)));
  }
  std::printf("  (CRLB for Td known, mean over runs; failures MMFM %d, MMFM+OE %d, SRIVC %d)\n",
              fails[0], fails[1], fails[2]);
  std::fflush(stdout);
}

namespace {

void print_order_table(const char* title, const IdentifyResult& r) {
  std::printf(" %s: chosen %s, validation fit %.2f %%, Td %.4f s\n", title,
              r.structure.name().c_str(), r.validation_fit_pct, r.delay_s);
  std::printf("   %-18s %10s %12s %14s %10s\n", "structure", "est fit %", "valid fit %", "BIC",
              "Td (s)");
  for (const StructureFit& s : r.table.rows)
    std::printf("   %-18s %10.2f %12.2f %14.1f %10.4f%s\n", s.structure.name().c_str(),
                s.estimation_fit_pct, s.validation_fit_pct, s.bic, s.model.delay_s,
                s.adequate ? " adequate" : "");
}

}  // namespace

void order_tables(const McConfig& cfg) {
  std::printf(
      "\n== Model-order selection (seed 001 style): estimate on the first half, "
      "validate on the second, the simplest structure within %.1f points of the best; "
      "seed %llu ==\n",
      kAdequacyMarginPct, static_cast<unsigned long long>(cfg.seed));
  const auto st = experiments::stornoway_record(cfg.seed, cfg.minutes);
  IdentifyOptions io;
  io.correlator.lags = cfg.lags;
  io.blocks = 0;
  print_order_table("Stornoway, SNR 0 dB, MMFM", identify(st.u, st.y, st.dt_s, io));
  io.methods = {IdentMethod::kSrivc};
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
  ir.methods = {IdentMethod::kSrivc};
  print_order_table("Rao-Garnier, SNR 10 dB, SRIVC (Td = 0 known)",
                    identify(rg.u, rg.y, rg.dt_s, ir));
}

}  // namespace rig::ident::bench
