// Alternator, grid and island load (DESIGN.md section 7), per unit on the set's rating.
//
//   2H dw/dt   = Pm/w - Pe/w - D dw,  Pm = Tm w            swing equation, w = 1 + dw
//   d(delta)/dt = w_b dw                                   w_b = 2 pi f0
//   grid:   Pe = E' V sin(delta) / X,  X = xd' + xe
//   island: Pe = P_L0 (1 + D_L dw)
// Optional flux decay  Td0' E'' = Efd - E' - (xd - xd') id,  id = (E' - V cos delta) / X,
// and a simple AVR  Ta Efd' = Ka (Vref - Vt) - Efd. Without them E' and Efd stay constant.
#pragma once

#include <complex>

#include "plantsim/plant/parameters.hpp"

namespace plantsim {

class Alternator {
 public:
  static constexpr int kStates = 4;  // dw, delta, E', Efd
  enum Index { kDw = 0, kDelta, kEq, kEfd };

  explicit Alternator(const Params& p) : p_(p) {}
  // Steady state at pe0_pu; throws ConfigError when the grid cannot carry it. Fixes the
  // island load and the AVR reference.
  void init(double pe0_pu, double* x);
  double electrical_power_pu(const double* x) const;
  double terminal_voltage_pu(const double* x) const;
  void derivatives(const double* x, double torque_pu, double* dx) const;
  // Linear torque-to-electrical-power response about x (used for the firing ripple).
  std::complex<double> torque_to_power(const double* x, std::complex<double> s) const;
  double load0_pu() const { return load0_pu_; }

 private:
  double reactance_pu() const { return p_[P::kAltXdp] + p_[P::kGridXe]; }
  bool grid() const { return p_[P::kGridConnected] > 0.5; }
  const Params& p_;
  double load0_pu_ = 0.0;
  double vref_pu_ = 1.0;
  double efd0_pu_ = 1.0;
};

}  // namespace plantsim
