// Backlash against a longer dead time (issue item 5): both add phase lag in the identified
// band, and while the play is small against the excitation it costs almost no gain. A dead
// time's lag does not depend on the amplitude; backlash's does (its describing function: the
// lag grows as b / A when the amplitude A falls). So when the diagnosis points at either, the
// monitor alternates the excitation between kLowScale and full scale for kBlocks blocks and
// compares the tracked delay's deviation at the two levels:
//   z = (d_low - d_high) / sqrt(se_low^2 + se_high^2)
// Backlash when z >= kSignificantZ (the lag grew at the lower amplitude), dead time otherwise.
#pragma once

#include <cmath>
#include <string>

namespace rig::monitor {

class AmplitudeTest {
 public:
  static constexpr double kLowScale = 0.5;  // the low level, share of the planned excitation
  static constexpr int kBlocks = 8;         // 4 at each level (~2.7 min)

  AmplitudeTest(std::string trigger, int onset_blocks)
      : trigger_(std::move(trigger)), onset_blocks_(onset_blocks) {}

  // The excitation scale of the block now running (low first).
  double scale() const { return index_ % 2 == 0 ? kLowScale : 1.0; }
  // The block just ended (at scale()): the delay's deviation and its standard error.
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
    return (low_.mean() - high_.mean()) / std::sqrt(1.0 / low_.w + 1.0 / high_.w);
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
