// The assembled plant ODE: governor, engine, alternator/grid and transducer lag in one state
// vector for CVODE. Inputs that are piecewise constant per tick (bias) or come from the
// history buffer (delayed fuel) are members set between solver calls.
//
// State layout: [Degov1 (6) | Engine (2) | Alternator (4) | transducer lag (1)]. CVODE
// integrates only the leading active_size() states: E' and Efd are constants without flux
// decay, and the transducer lag runs per tick on the output (TransducerLag), so the frozen
// tail is held here and a smaller dense system is factorised at every Newton setup.
#pragma once

#include <Eigen/Core>

#include "plantsim/plant/alternator.hpp"
#include "plantsim/plant/engine.hpp"
#include "plantsim/plant/engine_path.hpp"
#include "plantsim/plant/governor.hpp"
#include "plantsim/plant/ramps.hpp"
#include "plantsim/solver/cvode_solver.hpp"

namespace plantsim {

class GensetModel : public OdeSystem {
 public:
  static constexpr int kGov = 0;
  static constexpr int kEng = kGov + Degov1::kStates;
  static constexpr int kAlt = kEng + Engine::kStates;
  static constexpr int kMeas = kAlt + Alternator::kStates;
  static constexpr int kSize = kMeas + 1;

  explicit GensetModel(const Params& p) : p_(p), gov_(p_), eng_(p_), alt_(p_) {}
  GensetModel(const GensetModel&) = delete;  // the blocks refer to p_
  GensetModel& operator=(const GensetModel&) = delete;

  // Steady state at op.power_kw; validates limits (ConfigError). Returns the rack position.
  Eigen::VectorXd steady_state(double* rack0_pu);

  static int active_size(const Params& p) {
    return p[P::kAltFluxDecay] > 0.5 ? kMeas : kAlt + Alternator::kEq;
  }
  // Factors on solver.atol for the active states. The governor's z2 = z1' and a2 = a1' are
  // rates (pu/s) beside positions (pu): their tolerance is the position tolerance over the
  // block's fastest lag, T2 and min(T5, T6), the time in which such a rate error moves its
  // position by atol. Every other state gets atol itself.
  static Eigen::VectorXd atol_scale(const Params& p);
  // Full state whose tail beyond active_size() stays frozen; sets the active size.
  void set_frozen(const Eigen::VectorXd& full);
  int size() const override { return active_; }
  bool derivatives(double t, const double* x, double* dx) override;
  // The right-hand side with explicit inputs (used by derivatives() and the linearisation).
  void rhs(const double* x, double bias_pu, double fuel_delayed_pu, double* dx,
           bool limit_integrator = true) const;

  // Split: the bias path is solved outside (BiasPath) and the ODE's governor sees only the
  // state feedback, with its integrator unlimited. Otherwise the bias enters e directly.
  void set_split_bias_path(bool split) { split_ = split; }
  bool split_bias_path() const { return split_; }
  void set_bias_pu(double bias_pu) { bias_pu_ = bias_pu; }
  double bias_pu() const { return bias_pu_; }
  void set_delay_line(const FuelDelayLine* line) { delay_ = line; }
  // With a path the engine lags are solved outside (EnginePath): the ODE takes the torque
  // from it and its engine states are constant placeholders. nullptr: the ODE integrates them.
  void set_engine_path(const EnginePath* path) { engine_path_ = path; }
  const EnginePath* engine_path() const { return engine_path_; }
  // Running ramps: every right-hand-side evaluation sets the ramped parameters to their value
  // at its time; apply_ramps(t) does the same between solver calls.
  void set_ramps(const RampSet* ramps) { ramps_ = ramps; }
  void apply_ramps(double t_s) {
    if (ramps_ != nullptr && !ramps_->empty()) ramps_->apply(&p_, t_s);
  }

  double electrical_power_pu(const double* x) const { return alt_.electrical_power_pu(x + kAlt); }
  double terminal_voltage_pu(const double* x) const { return alt_.terminal_voltage_pu(x + kAlt); }
  std::complex<double> torque_to_measured_power(const double* x, std::complex<double> s) const;

  const Params& params() const { return p_; }
  Params& mutable_params() { return p_; }

 private:
  Params p_;
  Degov1 gov_;
  Engine eng_;
  Alternator alt_;
  double bias_pu_ = 0.0;
  bool split_ = false;
  const FuelDelayLine* delay_ = nullptr;
  const EnginePath* engine_path_ = nullptr;
  const RampSet* ramps_ = nullptr;
  int active_ = kSize;
  Eigen::VectorXd full_x_ = Eigen::VectorXd::Zero(kSize);
  Eigen::VectorXd full_dx_ = Eigen::VectorXd::Zero(kSize);
};

}  // namespace plantsim
