// SRIVC on degenerate data and on the public DaISy dryer record.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <vector>

#include "rig/ident/identify.hpp"
#include "rig/ident/srivc.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::ident {
namespace {

TEST(SrivcDegenerate, FilteredDerivativesRejectsUnusableDenominator) {
  const Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(50, 0.0, 1.0);
  EXPECT_THROW(model::filtered_derivatives(Eigen::VectorXd(), u, 0.1, 0.0), std::invalid_argument);
  EXPECT_THROW(model::filtered_derivatives(Eigen::VectorXd::Zero(3), u, 0.1, 0.0),
               std::invalid_argument);
  Eigen::Vector3d nan_den(1.0, std::numeric_limits<double>::quiet_NaN(), 2.0);
  EXPECT_THROW(model::filtered_derivatives(nan_den, u, 0.1, 0.0), std::invalid_argument);
  EXPECT_EQ(model::filtered_derivatives(Eigen::Vector3d(0.0, 1.0, 2.0), u, 0.1, 0.0).cols(), 2);
}

TEST(SrivcDegenerate, SingularInstrumentsAtEveryDelayThrowInsteadOfCrashing) {
  // A zero input makes the input columns of the instrument matrix zero, so every IV step is
  // singular: with the delay searched, the warm start used to be an empty denominator that
  // model::filtered_derivatives indexed out of range.
  const Eigen::Index n_samples = 400;
  const Eigen::VectorXd u = Eigen::VectorXd::Zero(n_samples);
  Eigen::VectorXd y(n_samples);
  for (Eigen::Index k = 0; k < n_samples; ++k) y(k) = std::sin(0.37 * static_cast<double>(k));
  SrivcOptions so;
  so.order = {2, 0};
  so.max_delay_s = 0.5;
  EXPECT_THROW(estimate_srivc(u, y, 0.08, so), std::invalid_argument);
  so.delay_s = 0.1;
  EXPECT_THROW(estimate_srivc(u, y, 0.08, so), std::invalid_argument);
}

TEST(SrivcDegenerate, DryerRecordAutomaticOrderAndDelay) {
  const char* shared = std::getenv("RIG_SHARED_DIR");
  if (!shared) GTEST_SKIP() << "RIG_SHARED_DIR not set";
  const std::filesystem::path path = std::filesystem::path(shared) / "data/daisy/dryer.dat";
  std::ifstream in(path);
  if (!in) GTEST_SKIP() << path << " missing";
  std::vector<double> uv, yv;
  double a = 0, b = 0;
  while (in >> a >> b) uv.push_back(a), yv.push_back(b);
  ASSERT_EQ(uv.size(), 1000u);
  const Eigen::VectorXd u =
      Eigen::Map<Eigen::VectorXd>(uv.data(), static_cast<Eigen::Index>(uv.size()));
  const Eigen::VectorXd y =
      Eigen::Map<Eigen::VectorXd>(yv.data(), static_cast<Eigen::Index>(yv.size()));
  IdentifyOptions opt;
  opt.methods = {IdentMethod::kSrivc};
  opt.correlator.lags = 125;  // min(256, N / 8), as rig identify chooses
  const IdentifyResult r = identify(u, y, 0.08, opt);
  std::printf("dryer SRIVC: order %d/%d, delay %.4f s, validation fit %.2f %%\n", r.order.n,
              r.order.m, r.delay_s, r.validation_fit_pct);
  EXPECT_TRUE(r.model.is_stable());
  EXPECT_GT(r.validation_fit_pct, 80.0);
  // Independent check: the chosen order re-estimated on the first half, simulated on the second.
  SrivcOptions so;
  so.order = r.order;
  const Eigen::Index h = u.size() / 2;
  const Eigen::VectorXd uc = u.array() - u.mean(), yc = y.array() - y.mean();
  const SrivcResult half = estimate_srivc(uc.head(h), yc.head(h), 0.08, so);
  const Eigen::VectorXd y_hat = simulate(half.model, uc, 0.08);
  EXPECT_GT(model::fit_percent(yc.tail(u.size() - h), y_hat.tail(u.size() - h)), 80.0);
}

}  // namespace
}  // namespace rig::ident
