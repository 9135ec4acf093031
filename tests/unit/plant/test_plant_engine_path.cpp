// EnginePath: the engine lags in closed form against CVODE integrating Engine::derivatives on
// the same rack history, the stop where the MAP limiter would act, and the plant handing the
// engine to the ODE and taking it back around a MAP-limited load step.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "plantsim/plant/config.hpp"
#include "plantsim/plant/engine_path.hpp"
#include "plantsim/plant/genset_plant.hpp"
#include "plantsim/solver/cvode_solver.hpp"

namespace plantsim {
namespace {

using std::chrono::milliseconds;
constexpr double kDt = 1e-3;

class EngineOde : public OdeSystem {
 public:
  EngineOde(const Params& p, const FuelDelayLine& line) : p_(p), eng_(p_), line_(line) {}
  int size() const override { return Engine::kStates; }
  bool derivatives(double t, const double* x, double* dx) override {
    eng_.derivatives(x, line_.at(t - dead_time_s(p_)), dx);
    return true;
  }

 private:
  Params p_;
  Engine eng_;
  const FuelDelayLine& line_;
};

// A rack history that changes slope at every sample: 0.7 pu plus a 3 Hz sine and a
// deterministic saw of +-0.01 pu.
double rack_pu(int k) { return 0.7 + 0.05 * std::sin(0.019 * k) + 0.01 * ((k * 7) % 5 - 2) / 2.0; }

// Days into a run, the corner times carry round-off of ~1e-11 s: extending must still add one
// knot per new sample (an earlier tolerance let the same corner repeat forever there).
TEST(EnginePath, ExtendsOneKnotPerSampleDaysIntoARun) {
  const Params p = preset("stornoway");
  for (const double start_s : {0.0, 8.64e4, 8.64e5 + 0.000123}) {
    FuelDelayLine line(kDt, 0.2, rack_pu(0));
    for (int k = 1; k <= 150; ++k) line.push(start_s + k * kDt, rack_pu(k));
    EnginePath path;
    ASSERT_TRUE(path.anchor(p, start_s + 0.1004, {0.69, 0.71}, line)) << start_s;
    for (int k = 151; k <= 2150; ++k) {
      line.push(start_s + k * kDt, rack_pu(k));
      ASSERT_TRUE(path.extend(line));
      path.prune(start_s + k * kDt - 0.01);
      ASSERT_NEAR(path.valid_until_s(), start_s + k * kDt + dead_time_s(p), 1e-6) << start_s;
    }
    EXPECT_LT(path.knots(), 600u) << start_s;
  }
}

TEST(EnginePath, ClosedFormMatchesTheEngineOde) {
  const Params p = preset("stornoway");
  FuelDelayLine line(kDt, 0.2, rack_pu(0));
  for (int k = 1; k <= 100; ++k) line.push(k * kDt, rack_pu(k));
  const double t0 = 0.0604;  // between two corners (they lie at k dt + Td)
  EnginePath path;
  ASSERT_TRUE(path.anchor(p, t0, {0.69, 0.71}, line));
  EXPECT_NEAR(path.valid_until_s(), 0.1 + dead_time_s(p), 1e-12);  // the newest corner
  EngineOde ode(p, line);
  SolverOptions tight;
  tight.rtol = 1e-12;
  tight.atol = 1e-14;
  CvodeSolver solver(ode, t0, Eigen::Vector2d(0.69, 0.71), tight);
  for (double t = t0 + 0.0007; t < path.valid_until_s(); t += 0.0031) {
    solver.advance_to(t);
    const EnginePath::State s = path.at(t);
    EXPECT_NEAR(s.torque_pu, solver.state()[Engine::kTorque], 1e-10) << t;
    EXPECT_NEAR(s.boost_pu, solver.state()[Engine::kBoost], 1e-10) << t;
    EXPECT_DOUBLE_EQ(path.torque_at(t), s.torque_pu);
  }
}

TEST(EnginePath, EndsWhereTheMapLimiterWouldAct) {
  const Params p = preset("stornoway");  // limit 0.4 + 0.9 boost: 1.03 pu at boost 0.7
  FuelDelayLine line(kDt, 0.2, 0.7);
  EnginePath path;
  ASSERT_TRUE(path.anchor(p, 0.0, {0.7, 0.7}, line));
  for (int k = 1; k <= 20; ++k) {
    line.push(k * kDt, k <= 10 ? 0.7 : 1.2);  // the sample at 11 ms is above the limit
    EXPECT_EQ(path.extend(line), k <= 10) << k;
  }
  EXPECT_FALSE(path.valid());
  EXPECT_NEAR(path.valid_until_s(), 0.010 + dead_time_s(p), 1e-12);  // the last clean corner
  EXPECT_NEAR(path.at(0.010 + dead_time_s(p)).torque_pu, 0.7, 1e-12);
}

TEST(EnginePath, PlantHandsTheEngineToTheOdeWhileTheMapLimiterActs) {
  Params p = preset("stornoway");
  p.set(P::kEngMapMin, 0.2, "test");  // a 20 % bias step then needs more fuel than the limit
  GensetPlant plant(p, {}, 1, milliseconds(1));
  EXPECT_TRUE(plant.engine_closed_form());
  plant.set_bias_pct(20.0);
  bool handed_back = false;
  for (int k = 0; k < 40000; ++k) {
    plant.step();
    handed_back = handed_back || !plant.engine_closed_form();
  }
  EXPECT_TRUE(handed_back);
  EXPECT_TRUE(plant.engine_closed_form());  // taken back once the boost has caught up
  EXPECT_NEAR(plant.electrical_power_kw(), 3500.0 + 0.2 * 4600.0, 10.0);
}

}  // namespace
}  // namespace plantsim
