// The thesis's online MMFM on exponentially averaged correlations (MMFM.md section 2, thesis
// 5-2, weight W) for the monitor's trends: after each block the second-order model's gain,
// natural frequency and damping from the averaged r_uu and r_yu. The equation set's settings
// (time scale, centres) are chosen once, on the first estimate, and then kept, so that the
// trend moves only with the data. The decisions use the parity equations (monitor.hpp); this
// is the engineer's familiar view of the same transfer function.
#pragma once

#include <optional>

#include "rig/ident/mmfm.hpp"
#include "rig/ident/parameters.hpp"
#include "rig/signal/streaming_correlator.hpp"

namespace rig::monitor {

class MmfmTracker {
 public:
  static constexpr double kWeight = 10.0;  // W of the exponential average (the thesis's)
  static constexpr Eigen::Index kLags = 256;

  MmfmTracker(double dt_s, Eigen::Index block_samples, double delay_s);
  void push(double u_coupled, double y_coupled) { corr_.push(u_coupled, y_coupled); }
  // The 2/0 figures from the averaged correlations; nullopt before a block has completed or
  // when the solve fails (an estimate is a view, never a reason to stop).
  std::optional<ident::DerivedFigures> estimate();
  void reset() { corr_.reset(); }  // a new segment: the averages restart

 private:
  signal::StreamingCorrelator corr_;
  std::optional<ident::MmfmSettings> settings_;
  double delay_s_;
};

}  // namespace rig::monitor
