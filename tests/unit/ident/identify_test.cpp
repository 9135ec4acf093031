#include "rig/ident/identify.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/bench/ident/ident_experiments.hpp"

namespace rig::ident {
namespace {

const DerivedFigures& truth() {
  static const DerivedFigures d = derived_figures(experiments::stornoway_tf(), Eigen::MatrixXd());
  return d;
}

TEST(Identify, MmfmStornowayAtZeroDbSnr) {
  // Seeds 21..23, 5 minutes, SNR 0 dB, order given, delay automatic.
  for (std::uint64_t seed = 21; seed < 24; ++seed) {
    const auto rec = experiments::stornoway_record(seed, 5.0);
    IdentifyOptions io;
    io.order = model::ModelOrder{2, 0};
    io.correlator.lags = 512;
    const IdentifyResult r = identify(rec.u.array() + 3.0, rec.y.array() + 100.0, rec.dt_s, io);
    ASSERT_TRUE(r.derived.valid);
    EXPECT_NEAR(r.derived.fn_hz, truth().fn_hz, 0.01 * truth().fn_hz) << "seed " << seed;
    EXPECT_NEAR(r.derived.zeta, truth().zeta, 0.10 * truth().zeta) << "seed " << seed;
    EXPECT_NEAR(r.derived.gain, truth().gain, 0.05 * truth().gain) << "seed " << seed;
    EXPECT_NEAR(r.delay_s, 0.06, 0.005) << "seed " << seed;
    EXPECT_EQ(r.std_error_method.rfind("block spread", 0), 0u) << r.std_error_method;
    EXPECT_GT(r.derived.fn_hz_std, 0.0);
    EXPECT_LT(r.derived.fn_hz_std, 0.01 * truth().fn_hz);
    EXPECT_GT(r.delay_std_s, 0.0);
    EXPECT_TRUE(std::isfinite(r.condition_number));
    ASSERT_EQ(r.parameters.size(), 5u);  // a2 a1 a0 b0 delay_s
    EXPECT_EQ(r.parameters.front().name, "a2");
    EXPECT_DOUBLE_EQ(r.parameters.front().value, 1.0);  // a_n = 1
    EXPECT_EQ(r.ryu.size(), 512);
    EXPECT_EQ(r.model_ryu.size(), r.ruu.size());
    EXPECT_GT(model::fit_percent(r.ryu.r, r.model_ryu.r), 80.0);
    EXPECT_NE(r.settings.find("hermite"), std::string::npos);
  }
}

TEST(Identify, SelectsSecondOrderForStornoway) {
  const auto rec = experiments::stornoway_record(31, 4.0, 10.0);
  IdentifyOptions io;
  io.correlator.lags = 512;
  io.blocks = 0;
  const IdentifyResult r = identify(rec.u, rec.y, rec.dt_s, io);
  // Orders 1..6 with every numerator order below, each with and without a dead time.
  ASSERT_EQ(r.table.rows.size(), 2u * 21u);
  EXPECT_EQ(r.order.n, 2);
  EXPECT_EQ(r.order.m, 0);
  EXPECT_TRUE(r.structure.delay_estimated);
  double first_order_fit = 0.0;
  for (const StructureFit& s : r.table.rows)
    if (s.structure.order.n == 1 && s.ok)
      first_order_fit = std::max(first_order_fit, s.validation_fit_pct);
  EXPECT_LT(first_order_fit, r.validation_fit_pct - 5.0);
  // SNR 10 dB bounds the achievable fit: 100 (1 - sqrt(0.1 / 1.1)) = 69.8 %.
  EXPECT_NEAR(r.validation_fit_pct, 69.8, 1.5);
  EXPECT_EQ(r.std_error_method, "asymptotic covariance");
  // The chosen structure is adequate and no adequate one has fewer parameters.
  ASSERT_NE(r.table.chosen_fit(), nullptr);
  for (const StructureFit& s : r.table.rows)
    if (s.adequate) {
      EXPECT_GE(s.structure.parameters(), r.structure.parameters());
    }
}

TEST(Identify, SrivcPathAndGivenDelay) {
  const auto rec = experiments::stornoway_record(41, 2.0);
  IdentifyOptions io;
  io.methods = {IdentMethod::kSrivc};
  io.order = model::ModelOrder{2, 0};
  io.delay_s = 0.06;
  const IdentifyResult r = identify(rec.u, rec.y, rec.dt_s, io);
  EXPECT_DOUBLE_EQ(r.delay_s, 0.06);
  EXPECT_NEAR(r.derived.fn_hz, truth().fn_hz, 0.01 * truth().fn_hz);
  EXPECT_TRUE(std::isnan(r.condition_number));
}

TEST(Identify, RejectsBadInput) {
  IdentifyOptions io;
  EXPECT_THROW(identify(Eigen::VectorXd::Zero(5000), Eigen::VectorXd::Zero(4999), 0.01, io),
               std::invalid_argument);
  EXPECT_THROW(identify(Eigen::VectorXd::Zero(100), Eigen::VectorXd::Zero(100), 0.01, io),
               std::invalid_argument);
  EXPECT_THROW(identify(Eigen::VectorXd::Zero(5000), Eigen::VectorXd::Zero(5000), 0.0, io),
               std::invalid_argument);
}

// When no structure of the table gives a model (here: a sixth-order MMFM whose modulating
// functions cannot fit a 16-lag correlation window), identify() says so with NoStableModel
// (rig identify: exit 1, no model), not with a usage error.
TEST(Identify, NoFittedStructureGivesNoStableModel) {
  const auto rec = experiments::stornoway_record(41, 2.0);
  IdentifyOptions io;
  io.order = model::ModelOrder{6, 5};
  io.methods = {IdentMethod::kMmfm};
  io.correlator.lags = 16;
  io.blocks = 0;
  EXPECT_THROW(identify(rec.u, rec.y, rec.dt_s, io), NoStableModel);
}

}  // namespace
}  // namespace rig::ident
