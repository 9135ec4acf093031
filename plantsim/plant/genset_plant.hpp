// The generator-set plant behind the Plant interface: the GensetModel ODE integrated by CVODE
// tick by tick, the fuel history buffer, the engine lags in closed form while no clamp acts
// (EnginePath), rack backlash, firing ripple and the measurement chain, with timed parameter
// changes applied exactly at their plant time, abruptly or as linear ramps (RampSet).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "plantsim/plant/bias_path.hpp"
#include "plantsim/plant/config.hpp"
#include "plantsim/plant/engine_path.hpp"
#include "plantsim/plant/measurement_chain.hpp"
#include "plantsim/plant/model.hpp"
#include "plantsim/plant/plant.hpp"
#include "plantsim/plant/ramps.hpp"

namespace plantsim {

class GensetPlant : public Plant {
 public:
  GensetPlant(const Params& params, std::vector<TimedChange> changes, std::uint64_t seed,
              std::chrono::nanoseconds tick);

  void set_bias_pct(double bias_pct) override { bias_pct_ = bias_pct; }
  void step() override;
  Measurement measure() const override { return last_; }
  std::chrono::nanoseconds tick() const override { return tick_; }
  std::uint64_t ticks() const override { return ticks_; }
  double rated_power_w() const override { return model_.params()[P::kRatedKw] * 1e3; }
  double external_bias_limit_pct() const override { return model_.params()[P::kGovExtBiasLimit]; }

  // Beyond the Plant interface (tests, benchmarks, linearisation checks).
  double time_s() const { return solver_->time(); }
  const Eigen::VectorXd& state() const { return x_; }  // full GensetModel layout
  const Params& params() const { return model_.params(); }
  double electrical_power_kw() const;  // true Pe, before the measurement chain
  double rack_pu() const { return backlash_.rack_pu(); }
  double actuator_pu() const { return actuator_pu_; }  // before backlash
  bool split_bias_path() const { return model_.split_bias_path(); }
  bool engine_closed_form() const { return model_.engine_path() != nullptr; }  // EnginePath
  SolverStats solver_stats() const { return solver_->stats(); }
  const std::string& last_error() const { return error_; }

 private:
  void apply(const TimedChange& change);
  void finish_ramp();
  void parameters_changed();
  void reconfigure();
  void configure_ripple();
  void refresh_ramped();
  void update_measurement();
  void advance_bias_path(double duration_s);
  void sync_state();
  // Restarts CVODE from x_ at t_s, with the engine in closed form when it holds there.
  void restart_solver(double t_s, bool try_engine_path = true);
  void retry_engine_path();
  double horizon_s(double t_now, double t_end, bool look_ahead) const;
  double engine_handback_s() const;
  bool advance_solver(double t_now, double t_end);

  GensetModel model_;
  std::chrono::nanoseconds tick_;
  double dt_s_;
  std::unique_ptr<FuelDelayLine> delay_;
  std::unique_ptr<CvodeSolver> solver_;
  EnginePath engine_path_;
  // Ticks with the engine in the ODE (a clamp acted) before the closed form is tried again:
  // a failed try costs one anchor (about a dead time of knots), a success one solver restart.
  static constexpr int kEngineRetryTicks = 100;
  int ode_engine_ticks_ = 0;
  Eigen::VectorXd x_;  // full state at the last output time
  Backlash backlash_;
  BiasPath bias_path_;
  TransducerLag transducer_;
  double actuator_pu_ = 0.0;
  FiringRipple ripple_;
  MeasurementChain chain_;
  std::vector<TimedChange> changes_;
  std::size_t next_change_ = 0;
  RampSet ramps_;
  // While a ramp moves the ripple's weights or gains they are refreshed every 10 ms of plant
  // time (a twentieth of stornoway's firing cycle; ramps last seconds to hours).
  static constexpr double kRippleRefreshS = 0.01;
  int ripple_refresh_ticks_ = 1;
  int ripple_ticks_ = 0;
  std::uint64_t ticks_ = 0;
  // Ticks without a bias change before CVODE may step beyond the next tick.
  static constexpr int kLookAheadAfterTicks = 20;
  int quiet_ticks_ = 0;
  double bias_pct_ = 0.0;
  double ripple_pu_ = 0.0;
  Measurement last_;
  std::string error_;
};

}  // namespace plantsim
