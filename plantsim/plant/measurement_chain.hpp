// Measurement chain of the electrical power (DESIGN.md section 7). The transducer lag
// Tt p' = Pe - p is a state of the ODE; everything after it acts per tick on the sample:
//   y = gain (p + ripple) P_rated + offset + drift + noise + A sin(2 pi f_pick t)     (kW)
//   quantised to q kW, then optionally AC-coupled by the analogue RC high-pass s RC/(1 + s RC).
// Drift is an Ornstein-Uhlenbeck process d_k = a d_{k-1} + sqrt(1 - a^2) sigma n_k,
// a = exp(-dt/tau). All randomness comes from one seeded generator: same seed, same samples.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "plantsim/plant/parameters.hpp"

namespace plantsim {

// Power transducer lag Tt y' = u - y, advanced per tick exactly for an input that is linear
// between the tick samples (first-order hold), a = exp(-h/Tt):
//   y_{k+1} = a y_k + (1 - a) u_k + (u_{k+1} - u_k) (1 - (Tt/h)(1 - a)).
// exp(x), recomputed only when x changes: the per-tick decays repeat tick after tick.
class ExpMemo {
 public:
  double operator()(double x) {
    if (x != x_) {
      x_ = x;
      y_ = std::exp(x);
    }
    return y_;
  }

 private:
  double x_ = 0.0;
  double y_ = 1.0;
};

class TransducerLag {
 public:
  void reset(double value) { y_ = u_ = value; }
  double advance(double u_next, double h_s, double lag_s) {
    const double a = decay_(-h_s / lag_s);
    y_ = a * y_ + (1.0 - a) * u_ + (u_next - u_) * (1.0 - lag_s / h_s * (1.0 - a));
    u_ = u_next;
    return y_;
  }
  double value() const { return y_; }

 private:
  double y_ = 0.0;
  double u_ = 0.0;
  ExpMemo decay_;
};

class MeasurementChain {
 public:
  MeasurementChain(std::uint64_t seed, double dt_s) : rng_(seed), dt_s_(dt_s) {}
  // p_pu: transducer output; ripple_pu: firing ripple at the transducer output.
  double sample_kw(const Params& p, double t_s, double p_pu, double ripple_pu);

 private:
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  double dt_s_;
  ExpMemo drift_decay_;
  double drift_kw_ = 0.0;
  double ac_lowpass_kw_ = 0.0;
  bool ac_started_ = false;
};

}  // namespace plantsim
