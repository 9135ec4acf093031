// The shape of a level event in the raw (uncoupled) power: what tells a sensor from the
// engine and from a load change when the transfer function cannot (issue item 5).
//
//   sensor step          the measured level jumps to its new value within a few samples
//                        (the transducer's own lag, ms) and stays: no transient, no
//                        governor action.
//   power loss recovered the power falls through the plant's dynamics (dead time, swing
//                        mode) and the governor's integrator brings it back to the old
//                        level within seconds: injector/cylinder loss, a fuel fault.
//   level change         the level moves through the plant's dynamics to a new value and
//                        stays: a load (setpoint) change, not a fault.
//
// Features, relative to the mean level over kPreS before the onset c:
//   jump    mean over the first kJumpS after c   (a transducer's step is complete there)
//   extreme the most deviating kExtremeAvgS mean within kExtremeS after c
//   final   mean over [kFinalFromS, kFinalToS] after c
// Classification (named thresholds below, each with its reason):
//   |final| >= kMinChange and |jump| >= kStepShare |final| and |extreme| <= kOvershoot |final|
//       -> sensor step
//   |extreme| >= kMinChange and extreme < 0 and |final| <= kRecoveredShare |extreme|
//       -> power loss recovered
//   |final| >= kMinChange -> level change;  otherwise unclear.
#pragma once

#include <string>
#include <vector>

namespace rig::monitor {

enum class ShapeKind { kUnclear, kSensorStep, kPowerLossRecovered, kLevelChange, kSlowDrift };
const char* to_string(ShapeKind kind);

struct EventShape {
  ShapeKind kind = ShapeKind::kUnclear;
  long onset = 0;        // sample index of the change in the given record
  double jump_kw = 0.0;  // see above
  double extreme_kw = 0.0;
  double final_kw = 0.0;
  double noise_kw = 0.0;  // std of the pre-onset samples
};

struct ShapeThresholds {
  double pre_s = 10.0;         // pre-onset level
  double jump_s = 0.1;         // a transducer settles in ms; the engine needs > 0.1 s
  double local_pre_s = 0.5;    // the level the jump is measured from
  double extreme_s = 8.0;      // the governor's recovery lasts seconds
  double extreme_avg_s = 0.2;  // smooths noise out of the extreme
  double final_from_s = 15.0;  // after the recovery
  double final_to_s = 30.0;
  double step_share = 0.6;         // a step has most of its change in the first 0.1 s
  double overshoot = 1.3;          // and no transient beyond its final value (a load step
                                   // through the governor overshoots by half its size and more)
  double recovered_share = 0.35;   // a recovered loss ends near the old level
  double min_change_sigmas = 6.0;  // a change must stand out of the pre-onset noise
  double min_change_kw = 0.0;      // and exceed this (set from P0)
};

// Record x (kW) sampled every dt_s; the change is searched within [from, to) samples (the
// onset c is where the level starts to move: the largest jump between 0.1 s means). The record
// must extend pre_s before `from` and final_to_s after `to`; otherwise kUnclear.
EventShape classify_shape(const std::vector<double>& x, double dt_s, long from, long to,
                          const ShapeThresholds& th = {});

// Moving average over n samples (centred; the ends average what exists). Over one engine
// cycle it removes the engine-order lines and all their harmonics.
std::vector<double> cycle_average(const std::vector<double>& x, long n);

}  // namespace rig::monitor
