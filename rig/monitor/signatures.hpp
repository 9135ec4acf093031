// The fault-signature table (issue item 5; docs/monitor.md explains each row): what was seen
// mapped onto a cause a station engineer understands, as a registry of rows with a score.
//
// Evidence (all standardised against the baseline's own spread, so 1 is one normal sigma):
//   z[parameter]  the tracked deviation of gain, damping, frequency, delay (joint fit)
//   isolated      the parameter whose single-parameter fit explains most of the residual
//   z_residual    residual energy left after the joint fit (unexplained: nonlinearity)
//   z_line        the engine-order line at the cycle frequency (a missing cylinder)
//   shape         the shape of the latest level event since the baseline (event_shape.hpp)
//   level_ratio   measured level change of a sensor-step event / the level before it
//
// Why the table needs more than the transfer function: in the identified band an injector
// loss (2 of 12: -1.6 dB) and a transducer gain error (+10 %: +0.8 dB) both move the gain
// flat, and the AC coupling removes the level. The line separates them (only a missing
// cylinder adds the half-order line); so does the event's shape (a recovered power dip
// against a step without transient) and, for a sensor, the level step matching the gain.
#pragma once

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rig/monitor/event_shape.hpp"

namespace rig::monitor {

struct Evidence {
  std::map<std::string, double> z;          // tracked parameter -> standardised deviation
  std::map<std::string, double> deviation;  // in display units (dB, %, ms)
  std::string isolated;                     // "" when nothing stands out
  double z_residual = 0.0;
  double z_line = 0.0;
  std::optional<EventShape> shape;
  double level_ratio = 0.0;  // sensor step: final / level before (0 when none)
  // The sensor test (sensor_test.hpp) when the level moved: the gain's deviation against a
  // gain error (z_gain) and against an offset (z_offset); NaN when it did not run.
  double sensor_z_gain = NAN;
  double sensor_z_offset = NAN;
  // The amplitude test (amplitude_test.hpp): the gain lost at the lower excitation level beyond
  // that at full, in standard errors; NaN when it did not run.
  double amplitude_z = NAN;
};

struct Diagnosis {
  std::string cause;                                   // "" when nothing matches
  std::string fault_class;                             // "additive" / "multiplicative"
  std::string check;                                   // what to check
  double confidence = 0.0;                             // best score / sum of scores (0..1)
  std::vector<std::pair<std::string, double>> scores;  // every row, for the evidence JSON
};

// The significance (in z) from which evidence counts.
inline constexpr double kSignificantZ = 3.0;

struct Signature {
  std::string cause;
  std::string fault_class;
  std::string check;
  double (*score)(const Evidence& e) = nullptr;  // 0: incompatible
};

const std::vector<Signature>& signature_table();
Diagnosis diagnose(const Evidence& e);

}  // namespace rig::monitor
