#include "rig/monitor/mmfm_tracker.hpp"

#include <exception>

namespace rig::monitor {
namespace {

signal::StreamingOptions streaming(double dt_s, Eigen::Index block_samples) {
  signal::StreamingOptions o;
  o.correlator.lags = MmfmTracker::kLags;
  o.correlator.dt_s = dt_s;
  o.averaging = signal::Averaging::kExponential;
  o.weight = MmfmTracker::kWeight;
  o.block_samples = block_samples;
  return o;
}

}  // namespace

MmfmTracker::MmfmTracker(double dt_s, Eigen::Index block_samples, double delay_s)
    : corr_(streaming(dt_s, block_samples)), delay_s_(delay_s) {}

std::optional<ident::DerivedFigures> MmfmTracker::estimate() {
  if (corr_.blocks() < 1) return std::nullopt;
  try {
    const signal::Correlation ruu = corr_.ruu(), ryu = corr_.ryu();
    ident::MmfmResult r;
    if (!settings_) {
      ident::MmfmOptions o;
      o.order = {2, 0};
      o.delay_s = delay_s_;
      r = ident::estimate_mmfm(ruu, ryu, o);
      settings_ = r.settings;
    } else {
      r = ident::mmfm_solve(ruu, ryu, {2, 0}, delay_s_, *settings_);
    }
    if (!r.derived.valid) return std::nullopt;
    return r.derived;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace rig::monitor
