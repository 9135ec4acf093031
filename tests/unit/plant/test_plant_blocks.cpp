// Each plant block against an analytic response (DESIGN.md section 7).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <functional>
#include <iostream>
#include <numbers>

#include "plantsim/plant/alternator.hpp"
#include "plantsim/plant/config.hpp"
#include "plantsim/plant/engine.hpp"
#include "plantsim/plant/governor.hpp"
#include "plantsim/plant/measurement_chain.hpp"
#include "plantsim/solver/cvode_solver.hpp"

namespace plantsim {
namespace {

using Rhs = std::function<void(double t, const double* x, double* dx)>;

class LambdaOde : public OdeSystem {
 public:
  LambdaOde(int n, Rhs f) : n_(n), f_(std::move(f)) {}
  int size() const override { return n_; }
  bool derivatives(double t, const double* x, double* dx) override {
    f_(t, x, dx);
    return true;
  }

 private:
  int n_;
  Rhs f_;
};

SolverOptions tight() {
  SolverOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  return o;
}

// e = R b constant, so xf - xf0 is the ramp response of K (1+sT4)(1+sT3) /
// ((1+sT5)(1+sT6)(1+sT1+s^2 T1 T2)) / s to R b, whose asymptote is K R b (t - tau) with the
// first moment tau = (T1 + T5 + T6) - (T3 + T4).
TEST(PlantBlocks, GovernorRampAsymptote) {
  const Params p = preset("stornoway");
  const Degov1 gov(p);
  const double pe0 = p[P::kPowerKw] / p[P::kRatedKw];
  const double bias = 0.01;
  LambdaOde ode(Degov1::kStates, [&](double, const double* x, double* dx) {
    gov.derivatives(x, pe0, 0.0, bias, dx);
  });
  Eigen::VectorXd x0(Degov1::kStates);
  gov.init(pe0, 0.7, x0.data());
  CvodeSolver solver(ode, 0.0, x0, tight());
  solver.advance_to(3.0);
  const double tau = p[P::kGovT1] + p[P::kGovT5] + p[P::kGovT6] - p[P::kGovT3] - p[P::kGovT4];
  const double expected = p[P::kGovK] * p[P::kGovR] * bias * (3.0 - tau);
  EXPECT_NEAR(solver.state()[Degov1::kXf] - 0.7, expected, 1e-7);
}

TEST(PlantBlocks, GovernorIntegratorDoesNotWindUp) {
  const Params p = preset("stornoway");
  const Degov1 gov(p);
  const double pe0 = p[P::kPowerKw] / p[P::kRatedKw];
  double bias = 0.5;
  LambdaOde ode(Degov1::kStates, [&](double, const double* x, double* dx) {
    gov.derivatives(x, pe0, 0.0, bias, dx);
  });
  Eigen::VectorXd x0(Degov1::kStates);
  gov.init(pe0, pe0, x0.data());
  CvodeSolver solver(ode, 0.0, x0, tight());
  const double tmax = p[P::kGovTmax];
  for (int k = 1; k <= 6000; ++k) {  // 6 s pushing against TMAX
    solver.advance_to(k * 1e-3);
    ASSERT_LE(solver.state()[Degov1::kXf], tmax + 1e-6);
  }
  EXPECT_NEAR(solver.state()[Degov1::kXf], tmax, 1e-6);
  bias = -0.5;
  solver.reinit(solver.time(), solver.state());
  solver.advance_to(6.2);
  // With wind-up the integrator would first have to unwind seconds of excess.
  EXPECT_LT(solver.state()[Degov1::kXf], tmax - 0.05);
}

TEST(PlantBlocks, GovernorDeadbandIgnoresSmallErrors) {
  Params p = preset("stornoway");
  p.set(P::kGovDeadband, 0.001, "test");
  const Degov1 gov(p);
  Eigen::VectorXd x(Degov1::kStates);
  gov.init(p[P::kPowerKw] / p[P::kRatedKw], 0.7, x.data());
  EXPECT_EQ(gov.error_pu(x.data(), 0.01, 0.0), 0.0);  // R b = 0.0005 < 0.001
  EXPECT_NEAR(gov.error_pu(x.data(), 0.05, 0.0), 0.0025 - 0.001, 1e-12);
}

TEST(PlantBlocks, BacklashMovesRackOnlyAfterThePlay) {
  Backlash b;
  b.reset(0.5);
  EXPECT_EQ(b.update(0.505, 0.02), 0.5);
  EXPECT_NEAR(b.update(0.53, 0.02), 0.52, 1e-12);
  EXPECT_NEAR(b.update(0.515, 0.02), 0.52, 1e-12);  // reversing inside the play
  EXPECT_NEAR(b.update(0.49, 0.02), 0.50, 1e-12);
}

TEST(PlantBlocks, EngineCombustionLagIsFirstOrder) {
  const Params p = preset("stornoway");
  const Engine eng(p);
  Eigen::VectorXd x0(Engine::kStates);
  eng.init(0.5, x0.data());
  LambdaOde ode(Engine::kStates,
                [&](double, const double* x, double* dx) { eng.derivatives(x, 0.7, dx); });
  CvodeSolver solver(ode, 0.0, x0, tight());
  const double tc = p[P::kEngCombustionLag];
  for (double t : {0.5 * tc, tc, 3.0 * tc}) {
    solver.advance_to(t);
    EXPECT_NEAR(solver.state()[Engine::kTorque], 0.7 - 0.2 * std::exp(-t / tc), 1e-7) << t;
  }
}

TEST(PlantBlocks, EngineMapLimiterCapsFuelByBoost) {
  const Params p = preset("stornoway");
  const Engine eng(p);
  const double x[2] = {0.3, 0.3};  // torque, boost
  double dx[2];
  eng.derivatives(x, 1.0, dx);
  const double limit = p[P::kEngMapMin] + p[P::kEngMapGain] * 0.3;
  EXPECT_NEAR(dx[Engine::kTorque], (limit - 0.3) / p[P::kEngCombustionLag], 1e-9);
  EXPECT_NEAR(dx[Engine::kBoost], (limit - 0.3) / p[P::kEngBoostLag], 1e-9);
}

TEST(PlantBlocks, DeadTimeAndCylinderFactor) {
  Params p = preset("stornoway");
  EXPECT_NEAR(dead_time_s(p), 30.0 / 600 + 60.0 / (12 * 600), 1e-15);
  EXPECT_DOUBLE_EQ(cylinder_factor(p), 1.0);
  p.set(P::kInjector3, 0.0, "test");
  EXPECT_NEAR(cylinder_factor(p), 11.0 / 12.0, 1e-15);
  p.set(P::kEngInjectorsOut, 2.0, "test");  // cylinders 1, 2 and 3 now dead
  EXPECT_NEAR(cylinder_factor(p), 9.0 / 12.0, 1e-15);
}

TEST(PlantBlocks, DelayLineInterpolatesTheHistory) {
  const double dt = 1e-3;
  FuelDelayLine line(dt, 0.2, 0.25);
  EXPECT_EQ(line.at(-0.05), 0.25);  // before any push: the initial steady state
  for (int k = 1; k <= 300; ++k) line.push(k * dt, 0.25 + k * dt);
  const double td = 0.0583333;
  EXPECT_NEAR(line.at(0.3 - td), 0.25 + 0.3 - td, 1e-12);
  EXPECT_NEAR(line.at(0.2504), 0.25 + 0.2504, 1e-12);
  EXPECT_NEAR(line.at(0.31), 0.25 + 0.3, 1e-12);  // beyond the newest sample: held
}

// Amplitude of the component at freq_hz over whole periods (single-bin DFT).
double amplitude(const std::vector<double>& y, double dt, double freq_hz) {
  std::complex<double> s{0.0, 0.0};
  for (std::size_t k = 0; k < y.size(); ++k) {
    s += y[k] * std::polar(1.0, -2.0 * std::numbers::pi * freq_hz * k * dt);
  }
  return 2.0 * std::abs(s) / static_cast<double>(y.size());
}

std::vector<double> ripple_record(const Params& p, double dt, int n) {
  FiringRipple r;
  r.configure(p, [](std::complex<double>) { return std::complex<double>(1.0, 0.0); });
  std::vector<double> y;
  for (int k = 0; k < n; ++k) y.push_back(r.advance(dt, 1.0, 0.8));
  return y;
}

TEST(PlantBlocks, FiringRippleBalancedAndWithDeadCylinder) {
  Params p = preset("stornoway");
  const double dt = 1e-4;
  const int n = 40000;  // 4 s = 20 engine cycles of 0.2 s
  const auto balanced = ripple_record(p, dt, n);
  const double sigma = 0.5 * p[P::kEngPulseWidth] * std::numbers::pi / 360.0;
  const double c12 = std::exp(-0.5 * 144.0 * sigma * sigma);
  EXPECT_LT(amplitude(balanced, dt, 5.0), 1e-9);  // no cycle harmonic
  EXPECT_NEAR(amplitude(balanced, dt, 60.0), 0.8 * 2.0 * c12, 1e-3 * 0.8 * 2 * c12);  // firing
  p.set(P::kInjector3, 0.0, "test");
  const auto dead = ripple_record(p, dt, n);
  const double c1 = std::exp(-0.5 * sigma * sigma);
  EXPECT_NEAR(amplitude(dead, dt, 5.0), 0.8 * 2.0 * c1 / 11.0, 1e-3);
}

TEST(PlantBlocks, SwingOscillatesAtTheAnalyticFrequency) {
  const Params p = preset("stornoway");
  Alternator alt(p);
  Eigen::VectorXd x0(Alternator::kStates);
  const double pe0 = p[P::kPowerKw] / p[P::kRatedKw];
  alt.init(pe0, x0.data());
  const double d0 = x0[Alternator::kDelta];
  x0[Alternator::kDelta] += 0.002;
  LambdaOde ode(Alternator::kStates,
                [&](double, const double* x, double* dx) { alt.derivatives(x, pe0, dx); });
  CvodeSolver solver(ode, 0.0, x0, tight());
  // Linearised: 2H dw' = -Ks ddelta - (D - P0) dw, ddelta' = w_b dw.
  const double ks = p[P::kAltE] * p[P::kGridV] * std::cos(d0) / (p[P::kAltXdp] + p[P::kGridXe]);
  const double wb = 2.0 * std::numbers::pi * p[P::kFreqHz];
  const double wn = std::sqrt(ks * wb / (2.0 * p[P::kAltH]));
  const double sigma = (p[P::kAltD] - pe0) / (4.0 * p[P::kAltH]);
  const double wd = std::sqrt(wn * wn - sigma * sigma);
  std::vector<double> crossings;
  double prev = 0.002;
  for (int k = 1; k <= 3000; ++k) {
    solver.advance_to(k * 1e-3);
    const double dd = solver.state()[Alternator::kDelta] - d0;
    if ((prev > 0.0) != (dd > 0.0)) crossings.push_back(k * 1e-3 - dd / (dd - prev) * 1e-3);
    prev = dd;
  }
  ASSERT_GE(crossings.size(), 6u);
  const double half_period = (crossings[5] - crossings[1]) / 4.0;
  EXPECT_NEAR(std::numbers::pi / half_period, wd, 0.005 * wd);
}

TEST(PlantBlocks, IslandLoadSettlesWhereTorqueBalances) {
  Params p = preset("stornoway_island");
  Alternator alt(p);
  Eigen::VectorXd x0(Alternator::kStates);
  const double pl0 = p[P::kPowerKw] / p[P::kRatedKw];
  alt.init(pl0, x0.data());
  const double tm = pl0 + 0.01;
  LambdaOde ode(Alternator::kStates,
                [&](double, const double* x, double* dx) { alt.derivatives(x, tm, dx); });
  CvodeSolver solver(ode, 0.0, x0, tight());
  solver.advance_to(20.0);
  // 0 = Tm - P_L0 (1 + D_L dw)/(1 + dw) - D dw, solved by Newton.
  const double dl = p[P::kLoadD], d = p[P::kAltD];
  double dw = 0.0;
  for (int i = 0; i < 50; ++i) {
    const double f = tm - pl0 * (1 + dl * dw) / (1 + dw) - d * dw;
    const double df = -pl0 * (dl - 1.0) / ((1 + dw) * (1 + dw)) - d;
    dw -= f / df;
  }
  EXPECT_NEAR(solver.state()[Alternator::kDw], dw, 1e-8);
}

TEST(PlantBlocks, MeasurementNoiseQuantisationAndAcCoupling) {
  Params p;
  p.set(P::kMeasNoise, 10.0, "test");
  p.set(P::kMeasQuant, 0.5, "test");
  const std::uint64_t seed = 42;
  std::cout << "seed " << seed << '\n';
  MeasurementChain chain(seed, 1e-3);
  const double base_kw = 0.5 * p[P::kRatedKw];
  double sum = 0.0, sum2 = 0.0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const double y = chain.sample_kw(p, k * 1e-3, 0.5, 0.0);
    EXPECT_NEAR(std::remainder(y, 0.5), 0.0, 1e-9);
    sum += y - base_kw;
    sum2 += (y - base_kw) * (y - base_kw);
  }
  const double mean = sum / n, rms = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 4.0 * 10.0 / std::sqrt(n));
  // 10 kW white noise + uniform quantisation error (q^2/12) = 10.001 kW; std error 0.5 %.
  EXPECT_NEAR(rms, std::sqrt(100.0 + 0.25 / 12.0), 0.03 * 10.0);

  Params ac;
  ac.set(P::kMeasAcRc, 0.5, "test");
  MeasurementChain coupled(seed, 1e-3);
  EXPECT_EQ(coupled.sample_kw(ac, 0.0, 0.5, 0.0), 0.0);  // DC level blocked from the start
  const double step_pu = 100.0 / ac[P::kRatedKw];
  EXPECT_NEAR(coupled.sample_kw(ac, 1e-3, 0.5 + step_pu, 0.0), 100.0, 1e-9);
  double y = 0.0;
  for (int k = 2; k <= 501; ++k) y = coupled.sample_kw(ac, k * 1e-3, 0.5 + step_pu, 0.0);
  EXPECT_NEAR(y, 100.0 * std::exp(-0.5 / 0.5), 1e-9);  // RC later: 1/e
}

TEST(PlantBlocks, MeasurementPickupAndGain) {
  Params p;
  p.set(P::kMeasPickup, 3.0, "test");
  p.set(P::kMeasGain, 1.1, "test");
  MeasurementChain chain(7, 1e-3);
  const double base = 1.1 * 0.5 * p[P::kRatedKw];
  EXPECT_NEAR(chain.sample_kw(p, 0.005, 0.5, 0.0) - base, 3.0, 1e-9);  // quarter period
  EXPECT_NEAR(chain.sample_kw(p, 0.015, 0.5, 0.0) - base, -3.0, 1e-9);
}

}  // namespace
}  // namespace plantsim
