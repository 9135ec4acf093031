// The engine's two lags solved in closed form between rack samples (DESIGN.md section 7).
//
// The delayed fuel f(t) = rack(t - Td) is the rack history interpolated linearly, so it has a
// corner at every sample t_j + Td: one per tick. With the engine inside CVODE the torque m
// (a lag of Tc = 8 ms in stornoway) has a jump of m'' at each corner and is itself a state in
// the error test, which held BDF to about two steps per tick under a bias that changes every
// tick (bench_plant). Both lags are linear while the MAP limiter and the zero-fuel clamp are
// inactive (0 <= f <= F0 + Fb boost), and then exact at any t within a segment:
//   T y' = c f - y,  f = f_a + s (t - t_a)
//   =>  y(t) = c f(t) - c T s + (y_a - c f_a + c T s) e^{-(t - t_a) / T}
// The path keeps (m, boost) at every corner ("knot") from the solver's time to the newest
// sample's corner, t_newest + Td. The ODE takes m(t) from here and holds its engine states
// constant, so CVODE integrates only the alternator and the governor's feedback, which see
// the corners one integration further down (about 0.4 steps per tick, same tolerances).
// Where a clamp would act the closed form ends (valid_until_s()) and the plant hands the
// engine back to the ODE.
#pragma once

#include <vector>

#include "plantsim/plant/engine.hpp"
#include "plantsim/plant/parameters.hpp"

namespace plantsim {

class EnginePath {
 public:
  struct State {
    double torque_pu = 0.0;
    double boost_pu = 0.0;
  };

  // The closed form needs the corners to be known before CVODE reaches them: Td >= one tick.
  static bool usable(const Params& p, double dt_s);
  // Restarts from the exact engine state at t_s under the parameters p and extends over the
  // rack history; false when a clamp acts before the newest corner (see valid()).
  bool anchor(const Params& p, double t_s, State s, const FuelDelayLine& line);
  // Adds the corners of samples pushed since; false once a clamp would act.
  bool extend(const FuelDelayLine& line);
  // Drops knots that end before t_s (the solver never evaluates before its current time).
  void prune(double t_s);

  bool valid() const { return valid_; }
  double valid_until_s() const { return knots_.back().t_s; }
  std::size_t knots() const { return knots_.size(); }  // stored (live and not yet compacted)
  double torque_at(double t_s) const;
  State at(double t_s) const;

 private:
  struct Knot {
    double t_s, fuel_pu, torque_pu, boost_pu;
  };
  const Knot& knot_before(double t_s) const;
  double slope_after(const Knot& k) const;  // fuel slope up to the next knot (0 past the last)
  bool push_corner(double t_s, double fuel_pu);
  double headroom_pu(double fuel_pu, double boost_pu) const;  // MAP limit minus fuel

  double tc_s_ = 1.0, tb_s_ = 1.0, c_ = 1.0, td_s_ = 0.0, map_min_pu_ = 0.0, map_gain_ = 0.0;
  double dt_s_ = 1.0, tick_decay_tc_ = 0.0, tick_decay_tb_ = 0.0;  // e^{-dt/Tc}, e^{-dt/Tb}
  std::vector<Knot> knots_;  // time order; [first_, end) live, compacted in place
  std::size_t first_ = 0;
  bool valid_ = false;
};

}  // namespace plantsim
