// Diesel engine (DESIGN.md section 7): fuel dead time, combustion lag, turbocharger boost with
// a boost-dependent fuel limit (MAP limiter), and per-cylinder torque contributions.
//
//   f_d(t) = rack(t - Td),  Td = 30/N + 60/(n N)   (half a revolution + one firing interval)
//   f_l    = min(f_d, F0 + Fb boost)                MAP limiter
//   Tc m'  = c f_l - m,  c = sum(health_k) / n       mean torque (pu), injector health cuts it
//                                                  (health_k: Params::injector, with
//                                                  engine.injectors_out folded in)
//   Tb b'  = c f_l - boost                           boost follows the delivered fuel
#pragma once

#include <complex>
#include <vector>

#include "plantsim/plant/parameters.hpp"

namespace plantsim {

double dead_time_s(const Params& p);      // engine.dead_time_s, or the formula when 0
double cylinder_factor(const Params& p);  // c = sum(health_k) / n
double map_fuel_limit_pu(const Params& p, double boost_pu);

class Engine {
 public:
  static constexpr int kStates = 2;  // mean torque m, boost
  enum Index { kTorque = 0, kBoost };

  explicit Engine(const Params& p) : p_(p) {}
  // Steady state delivering torque tm0_pu; returns the rack position needed.
  double init(double tm0_pu, double* x) const;
  void derivatives(const double* x, double fuel_delayed_pu, double* dx) const;
  static double torque_pu(const double* x) { return x[kTorque]; }

 private:
  const Params& p_;
};

// History of the rack position sampled every tick; read back by linear interpolation so the
// delayed fuel is continuous in time (the ODE right-hand side then stays continuous).
class FuelDelayLine {
 public:
  FuelDelayLine(double dt_s, double max_delay_s, double initial_pu);
  void push(double t_s, double rack_pu);  // t_s advances by dt_s per push
  double at(double t_s) const;            // rack(t_s); clamped to the stored span
  double newest_time_s() const { return t_newest_s_; }
  double dt_s() const { return dt_s_; }
  // The sample `back` ticks before the newest one (taken at newest_time_s() - back dt_s()).
  double sample(std::size_t back) const {
    return ring_[(head_ + ring_.size() - back) % ring_.size()];
  }

 private:
  double dt_s_;
  std::vector<double> ring_;
  std::size_t head_ = 0;  // index of the newest sample
  double t_newest_s_ = 0.0;
};

// Torque pulsation of the cylinders at harmonics h of the cycle frequency (N/120 Hz for a
// four-stroke engine), carried through the linear torque-to-measured-power response G(s) and
// added in the output path (it is far above the governor's bandwidth):
//   ripple = m Re{ sum_h A_h G(j h W) e^{j h phi} },  A_h = 2 c_h / n_eff sum_k health_k e^{-j h
//   phi_k}
// with c_h the Fourier coefficients of a Gaussian torque pulse. Balanced cylinders leave only
// the firing harmonics (h multiple of n); a dead cylinder adds every cycle harmonic.
class FiringRipple {
 public:
  // g_of_s: torque (pu) to measured power (pu) response at s.
  template <typename G>
  void configure(const Params& p, G&& g_of_s);
  double advance(double dt_s, double w_pu, double torque_pu);  // returns ripple power (pu)
  double phase_rad() const { return phase_rad_; }

 private:
  void set_weights(const Params& p);
  std::vector<std::complex<double>> weights_;  // A_h (h = 1..)
  std::vector<std::complex<double>> gains_;    // A_h G(j h W)
  std::vector<int> active_;                    // harmonics with a non-negligible gain
  double cycle_rad_s_ = 0.0;
  double phase_rad_ = 0.0;
  bool enabled_ = false;
};

template <typename G>
void FiringRipple::configure(const Params& p, G&& g_of_s) {
  set_weights(p);
  gains_.resize(weights_.size());
  for (std::size_t i = 0; i < weights_.size(); ++i) {
    const double w = static_cast<double>(i + 1) * cycle_rad_s_;
    gains_[i] = weights_[i] * g_of_s(std::complex<double>(0.0, w));
  }
  // Balanced cylinders cancel every harmonic but the firing ones; skip the cancelled ones.
  active_.clear();
  for (std::size_t i = 0; i < gains_.size(); ++i) {
    if (std::abs(weights_[i]) > 1e-12) active_.push_back(static_cast<int>(i) + 1);
  }
}

}  // namespace plantsim
