// A small seeded version of the Stornoway Monte Carlo (the full 200-run table is
// bench_ident_mc --case stornoway): 10-minute records at SNR 0 dB, seeds 100..105.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rig/ident/identify.hpp"
#include "tests/bench/ident/ident_experiments.hpp"

namespace rig::ident {
namespace {

TEST(StornowayMc, MmfmMeetsBiasAndSpreadTargets) {
  const DerivedFigures truth = derived_figures(experiments::stornoway_tf(), Eigen::MatrixXd());
  std::vector<double> fn, zeta, gain, td;
  for (std::uint64_t seed = 100; seed < 106; ++seed) {
    const auto rec = experiments::stornoway_record(seed, 10.0);
    IdentifyOptions io;
    io.order = model::ModelOrder{2, 0};
    io.correlator.lags = 512;
    io.blocks = 0;
    const IdentifyResult r = identify(rec.u, rec.y, rec.dt_s, io);
    fn.push_back(r.derived.fn_hz), zeta.push_back(r.derived.zeta);
    gain.push_back(r.derived.gain), td.push_back(r.delay_s);
  }
  const auto f = experiments::stats_of(fn), z = experiments::stats_of(zeta);
  const auto g = experiments::stats_of(gain), d = experiments::stats_of(td);
  EXPECT_LT(std::abs(f.mean / truth.fn_hz - 1.0), 0.005);
  EXPECT_LT(f.std / truth.fn_hz, 0.005);
  EXPECT_LT(std::abs(z.mean / truth.zeta - 1.0), 0.03);
  EXPECT_LT(z.std / truth.zeta, 0.05);
  EXPECT_LT(std::abs(g.mean / truth.gain - 1.0), 0.02);
  EXPECT_LT(g.std / truth.gain, 0.03);
  EXPECT_LT(std::abs(d.mean - 0.06), 0.005);
}

TEST(MmfmRefine, CorrelationOutputErrorKeepsNoiseFreeTruthAndTightensNoisyFits) {
  const auto rec = experiments::stornoway_record(7, 10.0);
  IdentifyOptions io;
  io.order = model::ModelOrder{2, 0};
  io.correlator.lags = 512;
  io.blocks = 0;
  const IdentifyResult plain = identify(rec.u, rec.y, rec.dt_s, io);
  io.mmfm.refine = true;
  const IdentifyResult refined = identify(rec.u, rec.y, rec.dt_s, io);
  // The refinement minimises exactly the correlation misfit, so it cannot be worse there.
  EXPECT_GE(model::fit_percent(refined.ryu.r, refined.model_ryu.r),
            model::fit_percent(plain.ryu.r, plain.model_ryu.r) - 1e-9);
  EXPECT_NE(refined.settings.find("refined"), std::string::npos);
  const auto clean = experiments::stornoway_record(7, 10.0, 300.0);
  const IdentifyResult exact = identify(clean.u, clean.y, clean.dt_s, io);
  EXPECT_NEAR(exact.derived.fn_hz, std::sqrt(11.05 / 0.07) / (2 * M_PI), 1e-3);
  EXPECT_NEAR(exact.delay_s, 0.06, 1e-4);
}

}  // namespace
}  // namespace rig::ident
