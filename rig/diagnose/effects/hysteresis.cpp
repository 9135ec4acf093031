// hysteresis: a Bouc-Wen loop in the actuator (blocks.hpp bouc_wen): every sustained movement
// of the input lags by up to half_width, engaging smoothly (shape_ratio) where a play engages
// at once. Plant: no plantsim parameter models a rounded loop; the nearest is the backlash
// width, which the note names.
#include <fmt/format.h>

#include <algorithm>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// The shape ratio gamma/beta: -0.9 (a slow, rounded engagement) to 1 (a play's sharp corner).
constexpr double kShapeRatioLo = -0.9;
constexpr double kShapeRatioHi = 1.0;

std::vector<ParamSpec> specs(const DataScales& s) {
  const double su = std::max(s.u_std, 1e-12);
  return {{"half_width", 1e-4 * su, 3.0 * su, true},
          {"shape_ratio", kShapeRatioLo, kShapeRatioHi, false}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const double su = pr.scales.u_std;
  return {{0.1 * su, 0.5}, {0.4 * su, 0.0}, {0.2 * su, -0.5}};
}

Eigen::VectorXd apply(const Problem&, const Params& p, Eigen::VectorXd v) {
  return bouc_wen(v, p[0], p[1]);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  return fmt::format(
      "the input's movements lag by up to {:.3g} ({:.0f} % of the input's standard deviation) "
      "through a hysteresis loop that engages {} (Bouc-Wen shape ratio {:.2f})",
      p[0], 100.0 * p[0] / std::max(pr.scales.u_std, 1e-12),
      p[1] > 0.5 ? "almost at once, like a play" : "gradually", p[1]);
}

}  // namespace

const EffectModel kHysteresisEffect{
    .id = Effect::kHysteresis,
    .name = "hysteresis",
    .kind = EffectKind::kInputNonlinearity,
    .description = "a hysteresis loop in the actuator: movements lag, engaging smoothly",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .explain = meaning,
    .generalises = Effect::kBacklash,  // shape_ratio 1: a play
    .in_feedback = true,               // a hysteretic spring (the Bouc-Wen oscillator)
};

}  // namespace rig::diagnose
