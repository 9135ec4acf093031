#include "plantsim/plant/ramps.hpp"

#include <algorithm>
#include <limits>

namespace plantsim {
namespace {

bool in(P id, std::initializer_list<P> set) {
  return std::find(set.begin(), set.end(), id) != set.end();
}

bool is_injector(P id) {
  const int k = static_cast<int>(id) - static_cast<int>(P::kInjector1);
  return k >= 0 && k < kMaxCylinders;
}

}  // namespace

void RampSet::start(const ParamRamp& ramp) {
  cancel(ramp.param);
  ramps_.push_back(ramp);
  classify();
}

void RampSet::cancel(P param) {
  std::erase_if(ramps_, [param](const ParamRamp& r) { return r.param == param; });
  classify();
}

double RampSet::next_end_s() const {
  double t = std::numeric_limits<double>::infinity();
  for (const ParamRamp& r : ramps_) t = std::min(t, r.t1_s);
  return t;
}

void RampSet::finish_next(Params* p) {
  if (ramps_.empty()) return;
  const auto first = std::min_element(ramps_.begin(), ramps_.end(),
                                      [](const auto& a, const auto& b) { return a.t1_s < b.t1_s; });
  p->set_unchecked(first->param, first->end);
  ramps_.erase(first);
  classify();
}

void RampSet::classify() {
  engine_ = dead_time_ = bias_path_ = setpoint_ = ripple_ = false;
  for (const ParamRamp& r : ramps_) {
    const P id = r.param;
    dead_time_ = dead_time_ || in(id, {P::kEngRpm, P::kEngDeadTime});
    engine_ = engine_ || is_injector(id) ||
              in(id, {P::kEngRpm, P::kEngDeadTime, P::kEngCombustionLag, P::kEngBoostLag,
                      P::kEngMapMin, P::kEngMapGain, P::kEngInjectorsOut});
    bias_path_ = bias_path_ || in(id, {P::kGovT1, P::kGovT2, P::kGovT3, P::kGovK, P::kGovT4,
                                       P::kGovT5, P::kGovT6});
    setpoint_ = setpoint_ || in(id, {P::kGovDeadband, P::kGovRate});
    // The ripple's gains follow the swing equation's operating point and the transducer lag;
    // the governor and the rest of the measurement chain do not enter them.
    const std::string_view name = spec(id).name;
    const bool output_only =
        name.starts_with("gov.") || (name.starts_with("meas.") && id != P::kMeasLag);
    ripple_ = ripple_ || !output_only;
  }
}

}  // namespace plantsim
