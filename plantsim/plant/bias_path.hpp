// The governor's setpoint path, solved exactly per tick (DESIGN.md section 7, DEGOV1).
//
// Control box and actuator lead-lags are linear, so the actuator position splits into
//   xf = G[e_x] + G[R b],  G(s) = K (1+sT3)(1+sT4) / (s (1+sT1+s^2 T1T2)(1+sT5)(1+sT6)),
// with e_x = Pref - g dw - R Pe_f the state feedback (integrated by CVODE with the plant) and
// R b the setpoint bias, piecewise constant per tick. G[R b] is advanced here by its exact
// zero-order-hold discretisation s_{k+1} = Phi s_k + Gamma r_k, so a bias change is no
// discontinuity in the ODE at all: the plant sees the bias only through the rack and the
// fuel dead time. The actuator limits act on the sum: after each tick the bias-path
// integrator is clamped so that TMIN <= xf <= TMAX, which removes the excess for good
// (no wind-up), with one-tick granularity.
#pragma once

#include <Eigen/Core>

#include "plantsim/plant/parameters.hpp"

namespace plantsim {

class BiasPath {
 public:
  static constexpr int kStates = 5;  // z1, z2, a1, a2 and the integrator xi
  using Vector = Eigen::Matrix<double, kStates, 1>;

  void configure(const Params& p, double dt_s);
  // Advances by dt_s (the configured tick) or, for a partial tick, by `duration_s`.
  void advance(double r_pu);
  void advance(double r_pu, double duration_s);
  // Keeps actuator_ode + xi within [lo, hi] (anti-windup of the sum).
  void clamp_integrator(double actuator_ode_pu, double lo_pu, double hi_pu);
  double integrator_pu() const { return s_[kStates - 1]; }
  const Vector& state() const { return s_; }
  void reset() { s_.setZero(); }

 private:
  void discretise(double duration_s, Eigen::Matrix<double, kStates, kStates>* phi,
                  Vector* gamma) const;
  Eigen::Matrix<double, kStates, kStates> a_ = Eigen::Matrix<double, kStates, kStates>::Zero();
  Vector b_ = Vector::Zero();
  Eigen::Matrix<double, kStates, kStates> phi_ =
      Eigen::Matrix<double, kStates, kStates>::Identity();
  Vector gamma_ = Vector::Zero();
  Vector s_ = Vector::Zero();
};

}  // namespace plantsim
