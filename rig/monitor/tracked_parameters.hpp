// The physical parameters `rig monitor` tracks one at a time (seed 002: single-parameter
// tracking), as a registry: each entry deforms the baseline transfer function along one
// physical direction, so that a fitted deviation reads in the engineer's units.
//
//   gain       G(s) (1 + d)                         shown in dB   (injector loss, transducer gain)
//   damping    zeta of the dominant pole pair (1 + d), DC gain kept   (alternator damping)
//   frequency  w_n of the dominant pole pair (1 + d), DC gain kept    (inertia, grid stiffness)
//   delay      Td + d seconds                       shown in ms   (fuel dead time, combustion lag)
//
// A baseline without a complex pole pair has no damping or frequency direction: those entries
// report unavailable() and are skipped.
#pragma once

#include <string>
#include <vector>

#include "rig/model/transfer_function.hpp"

namespace rig::monitor {

struct TrackedParameter {
  std::string name;    // "gain", "damping", "frequency", "delay"
  std::string unit;    // of the displayed deviation: "dB", "%", "%", "ms"
  double probe = 0.0;  // deviation used for the numerical sensitivity
  model::TransferFunction (*deform)(const model::TransferFunction& base, double d) = nullptr;
  double (*display)(double d) = nullptr;  // deviation d in `unit`
};

// The registry, in a fixed order (columns of every table and series).
const std::vector<TrackedParameter>& tracked_parameters();

// Index of the dominant (least damped) complex pole pair's first pole in tf.poles(), or -1.
int dominant_pair(const model::TransferFunction& tf);

// The baseline's dominant-pair figures (natural frequency Hz, damping ratio); {0, 0} if none.
struct ModeFigures {
  double fn_hz = 0.0;
  double zeta = 0.0;
};
ModeFigures dominant_mode(const model::TransferFunction& tf);

}  // namespace rig::monitor
