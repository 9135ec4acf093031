// Noise-free tables in the manner of thesis 5-1: triangle autocorrelation convolved with a
// known impulse response, MMFM fit, coefficients printed against the truth.
#include <cmath>
#include <cstdio>
#include <vector>

#include "rig/ident/mmfm.hpp"
#include "tests/bench/ident/mc_cases.hpp"
#include "tests/unit/ident/analytic_correlations.hpp"

namespace rig::ident::bench {
namespace {

using testing::make_tf;
using testing::triangle_pair;

// (s^2 + 2 s + 10) times a second factor, highest power first.
Eigen::VectorXd times_dominant_pair(const Eigen::VectorXd& other) {
  const Eigen::Vector3d pair(1.0, 2.0, 10.0);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(other.size() + 2);
  for (Eigen::Index i = 0; i < 3; ++i)
    for (Eigen::Index j = 0; j < other.size(); ++j) out(i + j) += pair(i) * other(j);
  return out;
}

void print_fit(const char* label, const MmfmResult& r) {
  const model::TransferFunction m = model::monic(r.model);
  std::printf(
      "  %-14s a1 %8.4f  a0 %8.4f  b0 %8.4f | fn %6.4f Hz zeta %6.4f gain %6.4f "
      "| Td %6.4f s | corr fit %6.2f %%\n",
      label, m.den(1), m.den(2), m.num(m.num.size() - 1), r.derived.fn_hz, r.derived.zeta,
      r.derived.gain, r.delay_s, r.correlation_fit_pct);
}

void fit_second_order(const char* label, const model::TransferFunction& plant) {
  const auto p = triangle_pair(plant, 0.05, 0.01, 1000, 400);
  MmfmOptions opt;
  opt.order = {2, 0};
  opt.delay_s = 0.0;
  print_fit(label, estimate_mmfm(p.ruu, p.ryu, opt));
  opt.delay_s.reset();
  opt.max_delay_s = 0.5;
  char l2[64];
  std::snprintf(l2, sizeof l2, "%s+Td", label);
  print_fit(l2, estimate_mmfm(p.ruu, p.ryu, opt));
}

}  // namespace

void noise_free_table() {
  struct Row {
    const char* name;
    model::TransferFunction tf;
    model::ModelOrder order;
  };
  const std::vector<Row> rows = {
      {"1/0 4/(s+2)", make_tf({4.0}, {1.0, 2.0}), {1, 0}},
      {"2/0 10/(s2+2s+10)", make_tf({10.0}, {1.0, 2.0, 10.0}), {2, 0}},
      {"2/1 (s+10)/(..)", make_tf({1.0, 10.0}, {1.0, 2.0, 10.0}), {2, 1}},
      {"2/0 +Td 0.137", make_tf({10.0}, {1.0, 2.0, 10.0}, 0.137), {2, 0}},
      {"3/0 pole -5", make_tf({50.0}, {1.0, 7.0, 20.0, 50.0}), {3, 0}},
      {"4/1 pairs", make_tf({10.0, 290.0}, {1.0, 6.0, 47.0, 98.0, 290.0}), {4, 1}},
      {"4/2", make_tf({2.0, 10.0, 290.0}, {1.0, 6.0, 47.0, 98.0, 290.0}), {4, 2}},
  };
  std::printf(
      "\n== Noise-free MMFM (thesis 5-1): triangle half-width 0.05 s, dt 0.01 s, "
      "1000 lags, zero at 400 ==\n");
  std::printf("  %-20s %-8s %14s %14s %12s %10s\n", "system", "solver", "max |rel err|",
              "Td est (s)", "cond", "S (s)");
  for (const Row& r : rows) {
    const auto p = triangle_pair(r.tf, 0.05, 0.01, 1000, 400);
    for (MmfmSolver solver : {MmfmSolver::kLeastSquares, MmfmSolver::kTotalLeastSquares}) {
      MmfmOptions opt;
      opt.order = r.order;
      if (r.tf.delay_s == 0.0) opt.delay_s = 0.0;
      opt.solver = solver;
      const MmfmResult res = estimate_mmfm(p.ruu, p.ryu, opt);
      const Eigen::VectorXd got = pack_parameters(monic(res.model));
      const Eigen::VectorXd want = pack_parameters(monic(r.tf));
      const double err = (got - want).cwiseQuotient(want).cwiseAbs().maxCoeff();
      std::printf("  %-20s %-8s %14.2e %14.5f %12.3g %10.4f\n", r.name,
                  solver == MmfmSolver::kLeastSquares ? "LS" : "TLS", err, res.delay_s,
                  res.condition_number, res.settings.scale_s);
    }
  }
}

void zero_shift_table() {
  std::printf(
      "\n== Thesis 5-1-1: zero-lag position within a 400-lag window (dt 0.02 s), "
      "noise-free, auto scale/centres; max |rel err| of the coefficients ==\n");
  std::printf("  %-10s %16s %16s %16s\n", "zero at", "1/0 4/(s+2)", "2/0 10/(..)", "S (2/0, s)");
  for (double frac : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8}) {
    const auto zi = static_cast<Eigen::Index>(frac * 400);
    double errs[2] = {0, 0}, scale = 0;
    int k = 0;
    for (const model::TransferFunction& tf :
         {make_tf({4.0}, {1.0, 2.0}), make_tf({10.0}, {1.0, 2.0, 10.0})}) {
      const auto p = triangle_pair(tf, 0.1, 0.02, 400, zi);
      MmfmOptions opt;
      opt.order = {tf.order(), 0};
      opt.delay_s = 0.0;
      try {
        const MmfmResult r = estimate_mmfm(p.ruu, p.ryu, opt);
        const Eigen::VectorXd got = pack_parameters(monic(r.model)),
                              want = pack_parameters(model::monic(tf));
        errs[k] = (got - want).cwiseQuotient(want).cwiseAbs().maxCoeff();
        scale = r.settings.scale_s;
      } catch (const std::exception&) {
        errs[k] = std::nan("");
      }
      ++k;
    }
    std::printf("  %8.0f %% %16.2e %16.2e %16.4f\n", frac * 100, errs[0], errs[1], scale);
  }
}

void thesis_513_table() {
  std::printf(
      "\n== Thesis 5-1-3: dominant pair -1+-3j, unit DC gain, fitted 2/0 (monic); "
      "true a1 2, a0 10, b0 10, fn %.4f Hz, zeta %.4f ==\n",
      std::sqrt(10.0) / (2 * M_PI), 1.0 / std::sqrt(10.0));
  std::printf(" third order, real pole at -p:\n");
  for (double p : {20.0, 10.0, 5.0, 3.0, 2.0, 1.0}) {
    const model::TransferFunction plant{Eigen::VectorXd::Constant(1, 10.0 * p),
                                        times_dominant_pair(Eigen::Vector2d(1.0, p)), 0.0};
    char label[32];
    std::snprintf(label, sizeof label, "p=%g", p);
    fit_second_order(label, plant);
  }
  std::printf(" fourth order, second pair at -a+-bj:\n");
  const double pairs[][2] = {{20, 20}, {10, 10}, {5, 5}, {3, 6}, {2, 2}};
  for (const auto& ab : pairs) {
    const double a = ab[0], b = ab[1], w2 = a * a + b * b;
    const model::TransferFunction plant{Eigen::VectorXd::Constant(1, 10.0 * w2),
                                        times_dominant_pair(Eigen::Vector3d(1.0, 2.0 * a, w2)),
                                        0.0};
    char label[32];
    std::snprintf(label, sizeof label, "-%g+-%gj", a, b);
    fit_second_order(label, plant);
  }
}

}  // namespace rig::ident::bench
