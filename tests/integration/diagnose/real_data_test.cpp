// Real measured records (RIG_SHARED_DIR/data, README there): the linear TF that identify()
// fits is the model; the diagnosis must run, and on the benchmarks built around a known
// nonlinearity it must not call the linear model sufficient. Verdicts and fits are printed.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "rig/diagnose/diagnose.hpp"
#include "rig/ident/identify.hpp"
#include "rig/io/recording.hpp"

namespace fs = std::filesystem;

namespace {

struct RealCase {
  const char* file;
  const char* in;
  const char* out;
  std::optional<double> dt_s;
  Eigen::Index from, to;  // 0-based half-open row range (to = -1: the end)
  bool known_nonlinear;   // a linear model must not be judged sufficient
};

std::optional<fs::path> data_dir() {
  const char* d = std::getenv("RIG_SHARED_DIR");
  if (!d) return std::nullopt;
  const fs::path p = fs::path(d) / "data";
  return fs::exists(p) ? std::optional<fs::path>(p) : std::nullopt;
}

rig::diagnose::DiagnoseResult run_case(const fs::path& root, const RealCase& c, double* model_fit) {
  rig::io::ReadOptions ro;
  ro.columns = {c.in, c.out};
  ro.dt_s = c.dt_s;
  const auto rec = rig::io::read_recording(root / c.file, ro);
  const Eigen::Index to = c.to < 0 ? rec.rows() : c.to;
  const Eigen::VectorXd u = rec.column(c.in).segment(c.from, to - c.from);
  const Eigen::VectorXd y = rec.column(c.out).segment(c.from, to - c.from);
  rig::ident::IdentifyOptions io;
  io.method =
      rig::ident::IdentMethod::kMmfm;  // (SRIVC segfaulted on dryer.dat at the time of writing)
  io.correlator.lags = std::min<Eigen::Index>(256, u.size() / 8);
  const auto id = rig::ident::identify(u, y, rec.dt_s, io);
  *model_fit = id.validation_fit_pct;
  return rig::diagnose::diagnose({id.model, u, y, rec.dt_s, std::nullopt});
}

TEST(RealData, VerdictsOnPublicBenchmarks) {
  const auto root = data_dir();
  if (!root) GTEST_SKIP() << "RIG_SHARED_DIR/data not available";
  const RealCase cases[] = {
      {"daisy/dryer.dat", "1", "2", 0.08, 0, -1, false},
      {"nonlinear_benchmarks/silverbox/SNLS80mV.csv", "V1", "V2", 1.0 / 610.35, 40650, 60650, true},
      {"nonlinear_benchmarks/cascaded_tanks/dataBenchmark.csv", "uEst", "yEst", std::nullopt, 0, -1,
       true},
      {"nonlinear_benchmarks/wiener_hammerstein_2009/WienerHammerBenchmark.csv", "uBenchMark",
       "yBenchMark", 1.0 / 51200.0, 5200, 25200, true},
      {"daisy/heating_system.dat", "2", "3", 2.0, 0, -1, false},
  };
  for (const auto& c : cases) {
    double model_fit = 0.0;
    rig::diagnose::DiagnoseResult r;
    try {
      r = run_case(*root, c, &model_fit);
    } catch (const std::exception& e) {
      std::printf("%s: not diagnosed: %s\n", c.file, e.what());
      ADD_FAILURE() << c.file << ": " << e.what();
      continue;
    }
    const auto* h = r.chosen();
    std::printf(
        "%s: identified model validation fit %.1f %%; verdict %s; validation fit %.1f -> %s %%; "
        "%.1f s\n  %s\n",
        c.file, model_fit, r.verdict.c_str(), r.validation_fit_before_pct,
        h ? std::to_string(h->validation_fit_after).c_str() : "-", r.elapsed_s,
        r.explanation.c_str());
    for (std::size_t i = 0; i < std::min<std::size_t>(3, r.hypotheses.size()); ++i) {
      const auto& hh = r.hypotheses[i];
      std::printf("  #%zu %s [", i + 1, hh.name().c_str());
      for (const auto& e : hh.effects)
        for (double p : e.params) std::printf(" %.4g", p);
      std::printf(" ]: validation fit %.1f -> %.1f, score %+.2f\n", hh.validation_fit_before,
                  hh.validation_fit_after, hh.score);
    }
    if (c.known_nonlinear) {
      EXPECT_NE(r.verdict, "none") << c.file;
    }
  }
}

}  // namespace
