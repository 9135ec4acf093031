// Parameters moving linearly in plant time (--fault NAME=VALUE@t=SECONDS,ramp=SECONDS). The
// ODE reads them at every right-hand-side evaluation (GensetModel::derivatives), so the model
// sees a continuous ramp, not a staircase; the per-tick output path reads them at each tick's
// end. What is derived from them is refreshed by GensetPlant while they run: the engine's
// closed form stands aside for a ramp of an engine parameter (the engine lags go back into
// the ODE), the bias path is re-discretised and the firing ripple re-weighted every tick.
#pragma once

#include <vector>

#include "plantsim/plant/parameters.hpp"

namespace plantsim {

class RampSet {
 public:
  // Starts a ramp; one already running on the same parameter is dropped (the newer change
  // wins from its start, from the value the parameter has then).
  void start(const ParamRamp& ramp);
  void cancel(P param);
  bool empty() const { return ramps_.empty(); }
  double next_end_s() const;  // infinity when none runs
  // Ends the ramp that ends first: its parameter takes the final value (ParamRamp::end).
  void finish_next(Params* p);
  // Sets every ramped parameter to its value at t_s.
  void apply(Params* p, double t_s) const {
    for (const ParamRamp& r : ramps_) p->set_unchecked(r.param, r.at(t_s));
  }
  // Which derived quantities a running ramp touches.
  bool touches_engine() const { return engine_; }        // EnginePath's constants
  bool touches_dead_time() const { return dead_time_; }  // the fuel dead time
  bool touches_bias_path() const { return bias_path_; }  // BiasPath's discretisation
  bool touches_setpoint() const { return setpoint_; }    // deadband, rate limit
  bool touches_ripple() const { return ripple_; }        // FiringRipple's weights and gains

 private:
  void classify();
  std::vector<ParamRamp> ramps_;
  bool engine_ = false;
  bool dead_time_ = false;
  bool bias_path_ = false;
  bool setpoint_ = false;
  bool ripple_ = false;
};

}  // namespace plantsim
