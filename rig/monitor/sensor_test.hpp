// A transducer gain error against a transducer offset (issue item 5). Both move the measured
// level; only the gain error also moves the transfer function's gain, and by the same ratio:
//   gain error  g - 1:  level ratio r = (level - ref) / ref = g - 1  and  d_gain = g - 1
//   offset:             level ratio r = offset / ref               and  d_gain = 0
// Over the blocks after the level moved (a step, or a slow drift), the inverse-variance
// weighted means of r and of the tracked gain deviation d are compared with both hypotheses:
//   z_gain = (d - r) / se,  z_offset = d / se,  se = the standard error of the mean of d.
// The test decides once the hypotheses stand kSeparation standard errors apart (|r| / se), or
// after kMaxBlocks with what there is; each hypothesis' probability is its Gaussian likelihood
// share.
#pragma once

#include <cmath>

namespace rig::monitor {

class SensorTest {
 public:
  static constexpr double kSeparation = 4.0;  // hypotheses this many standard errors apart
  static constexpr int kMaxBlocks = 18;       // ~6 min of blocks: then decide anyway

  SensorTest(double ref_kw, int min_blocks) : ref_kw_(ref_kw), min_blocks_(min_blocks) {}

  // One block: its mean measured level and the gain's deviation d with standard error se.
  void add(double level_kw, double d, double se) {
    if (!(se > 0.0) || !std::isfinite(d) || ref_kw_ <= 0.0) return;
    const double w = 1.0 / (se * se);
    sw_ += w;
    swd_ += w * d;
    swr_ += w * (level_kw - ref_kw_) / ref_kw_;
    ++blocks_;
  }
  bool decided() const {
    if (blocks_ < min_blocks_ || sw_ <= 0.0) return false;
    return std::abs(ratio()) * std::sqrt(sw_) >= kSeparation || blocks_ >= kMaxBlocks;
  }
  double ratio() const { return sw_ > 0.0 ? swr_ / sw_ : 0.0; }
  double gain() const { return sw_ > 0.0 ? swd_ / sw_ : 0.0; }
  double z_gain() const { return (gain() - ratio()) * std::sqrt(sw_); }
  double z_offset() const { return gain() * std::sqrt(sw_); }
  double p_gain() const {
    const double a = std::exp(-0.5 * z_gain() * z_gain());
    const double b = std::exp(-0.5 * z_offset() * z_offset());
    return a + b > 0.0 ? a / (a + b) : 0.5;
  }
  int blocks() const { return blocks_; }
  double ref_kw() const { return ref_kw_; }

 private:
  double ref_kw_;
  int min_blocks_;
  double sw_ = 0.0, swd_ = 0.0, swr_ = 0.0;
  int blocks_ = 0;
};

}  // namespace rig::monitor
