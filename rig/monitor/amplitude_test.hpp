// Backlash against a longer dead time (issue item 5): both add phase lag in the identified
// band, and the joint fit reads play partly as delay. A dead time does not depend on the
// amplitude; backlash does: its describing function's gain falls as the amplitude A falls
// towards the play b (below it nothing passes). So when the diagnosis points at either, the
// monitor alternates the excitation between kLowScale and full scale for kBlocks blocks and
// compares the tracked gain's deviation at the two levels:
//   z = (d_high - d_low) / sqrt(se_low^2 + se_high^2)
// Backlash when z >= kPlayZ (more gain lost at the lower amplitude), dead time otherwise. (Measured
// on plantsim: the fitted delay is no discriminator, it even shrinks at the lower level as the gain
// loss takes over.)
#pragma once

#include <cmath>
#include <string>

namespace rig::monitor {

class AmplitudeTest {
 public:
  // The low level, share of the planned excitation: a third (rather than a half) gives the
  // larger contrast for the same standard errors (play's gain loss grows as b / A).
  static constexpr double kLowScale = 1.0 / 3.0;
  static constexpr int kBlocks = 16;  // 8 at each level (~5.5 min)
  // One-sided: a dead-time change is named play with probability 2.3 % (Gaussian errors);
  // measured on plantsim, dead-time changes gave z within +-1.

  static constexpr double kPlayZ = 2.0;

  AmplitudeTest(std::string trigger, int onset_blocks)
      : trigger_(std::move(trigger)), onset_blocks_(onset_blocks) {}

  // The excitation scale of the block now running (low first).
  double scale() const { return index_ % 2 == 0 ? kLowScale : 1.0; }
  // The block just ended (at scale()): the gain's deviation and its standard error.
  void add(double d, double se) {
    if (se > 0.0 && std::isfinite(d)) {
      const double w = 1.0 / (se * se);
      (index_ % 2 == 0 ? low_ : high_).add(d, w);
    }
    ++index_;
  }
  bool done() const { return index_ >= kBlocks; }
  double z() const {
    if (low_.w <= 0.0 || high_.w <= 0.0) return 0.0;
    return (high_.mean() - low_.mean()) / std::sqrt(1.0 / low_.w + 1.0 / high_.w);
  }
  double low() const { return low_.mean(); }
  double high() const { return high_.mean(); }
  const std::string& trigger() const { return trigger_; }
  int onset_blocks() const { return onset_blocks_ + index_; }

 private:
  struct Mean {
    double sw = 0.0, swd = 0.0, w = 0.0;
    void add(double d, double weight) {
      sw += weight;
      swd += weight * d;
      w = sw;
    }
    double mean() const { return sw > 0.0 ? swd / sw : 0.0; }
  };
  std::string trigger_;
  int onset_blocks_;
  int index_ = 0;
  Mean low_, high_;
};

}  // namespace rig::monitor
