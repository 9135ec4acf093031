// DEGOV1 governor (PSS/E form) with electrical-power feedback droop (DESIGN.md section 7).
//
//   e   = Pref + R b - g dw - R Pe/(1 + s TE)              (all per unit, b = bias)
//   c   = (1 + s T3) / (1 + s T1 + s^2 T1 T2) e            control box
//   v   = K (1 + s T4) / ((1 + s T5)(1 + s T6)) c          actuator lead-lags
//   xf' = v, TMIN <= xf <= TMAX                             actuator integrator, no wind-up
//
// Bias: the setpoint bias b (fraction of rated power) is scaled by R before the summing
// junction. With the integrator, steady state needs e = 0, so dPe = (R b)/R = b: a 1 % bias
// moves the set by 1 % of rated power when grid-connected. Pref = R P0 holds the operating
// point. g weights the speed error (1 = DEGOV1; a kW-controlled set uses a small weight).
// Optional: actuator rate limit |xf'| <= rate, a deadband on e, and rack backlash (Backlash,
// applied per tick between the actuator and the fuel rack).
#pragma once

#include "plantsim/plant/parameters.hpp"

namespace plantsim {

class Degov1 {
 public:
  static constexpr int kStates = 6;  // pe_f, z1, z2, a1, a2, xf
  enum Index { kPeFilt = 0, kZ1, kZ2, kA1, kA2, kXf };

  explicit Degov1(const Params& p) : p_(p) {}
  // Steady state at electrical power pe0_pu with actuator position xf0_pu.
  void init(double pe0_pu, double xf0_pu, double* x) const;
  double pref_pu() const;  // R P0, from op.power_kw
  // Summing-junction error with the deadband applied.
  double error_pu(const double* x, double bias_pu, double dw_pu) const;
  // limit_integrator = false leaves xf a plain integrator (when the limits act elsewhere,
  // see BiasPath).
  void derivatives(const double* x, double pe_pu, double dw_pu, double bias_pu, double* dx,
                   bool limit_integrator = true) const;
  static double actuator_pu(const double* x) { return x[kXf]; }

 private:
  const Params& p_;
};

// Mechanical play of width w between actuator and rack: the rack moves only when the
// actuator pushes on one face, rack = xf -+ w/2.
class Backlash {
 public:
  void reset(double position_pu) { rack_pu_ = position_pu; }
  double update(double actuator_pu, double width_pu) {
    const double half = 0.5 * width_pu;
    if (actuator_pu > rack_pu_ + half) rack_pu_ = actuator_pu - half;
    if (actuator_pu < rack_pu_ - half) rack_pu_ = actuator_pu + half;
    return rack_pu_;
  }
  double rack_pu() const { return rack_pu_; }

 private:
  double rack_pu_ = 0.0;
};

}  // namespace plantsim
