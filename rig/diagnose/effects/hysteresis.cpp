// hysteresis: a Bouc-Wen loop in the actuator (blocks.hpp bouc_wen). Its hysteretic
// variable z follows the input's movements and saturates at +-half_width, engaging smoothly
// (shape_ratio) or at once (1); the output is v = a u + b z:
//   a play      (a 1, b -1): v = u - z, every sustained movement lags by up to half_width;
//   elasto-plastic (b > 0): v follows small movements with slope a + b and yields beyond
//               +-half_width to slope a (a linkage or spring that slips, gensim's actuator). Plant:
//               no plantsim parameter models a rounded loop; the nearest is the backlash
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

// The shares a and b: at most 1.2 (a fifth more than the model's own gain).
constexpr double kShareMax = 1.2;

// A fit whose shape ratio stops within this share of the range from its rounded end asked
// for a still more gradual engagement, which is no loop but a lag: not credible (the
// resonance's damping bound and the front lag's bound are treated alike). On gensim a
// combustion lag read as a loop with shape -0.90 and a half width of 1.6 input standard
// deviations; every true loop there has a shape ratio of -0.45 or more.
constexpr double kRoundedEndShare = 0.02;

bool credible(const AppliedEffect& e, const DataScales&) {
  return e.params[1] > kShapeRatioLo + kRoundedEndShare * (kShapeRatioHi - kShapeRatioLo);
}

std::vector<ParamSpec> specs(const DataScales& s) {
  const double su = std::max(s.u_std, 1e-12);
  return {{"half_width", 1e-4 * su, 3.0 * su, true},
          {"shape_ratio", kShapeRatioLo, kShapeRatioHi, false},
          {"linear_share", 0.0, kShareMax, false},
          {"hysteretic_share", -kShareMax, kShareMax, false}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const double su = pr.scales.u_std;
  return {{0.1 * su, 0.5, 1.0, -1.0},
          {0.4 * su, 0.0, 1.0, -1.0},
          {0.2 * su, -0.5, 1.0, -1.0},
          {0.5 * su, 0.9, 0.3, 0.7},
          {1.0 * su, 0.9, 0.3, 0.7}};
}

Eigen::VectorXd apply(const Problem&, const Params& p, Eigen::VectorXd v) {
  const Eigen::VectorXd z = v - bouc_wen(v, p[0], p[1]);
  return p[2] * v + p[3] * z;
}

double step(const Params& p, StepState& s, double x, double, double) {
  const double du = s.started ? x - s.last_in : 0.0;
  s.memory = bouc_wen_step(s.memory, du, p[0], p[1]);
  s.last_in = x;
  s.started = true;
  return p[2] * x + p[3] * s.memory;
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  if (p[3] > 0.0)
    return fmt::format(
        "a hysteresis loop that follows small movements with slope {:.2f} and yields beyond "
        "+-{:.3g} ({:.0f} % of the input's standard deviation) to slope {:.2f} (elasto-plastic, "
        "Bouc-Wen shape ratio {:.2f})",
        p[2] + p[3], p[0], 100.0 * p[0] / std::max(pr.scales.u_std, 1e-12), p[2], p[1]);
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
    .step = step,
    .explain = meaning,
    .generalises = Effect::kBacklash,  // shape_ratio 1: a play
    .in_feedback = true,               // a hysteretic spring (the Bouc-Wen oscillator)
    .needs_direction_evidence = true,
    .credible = credible,
};

}  // namespace rig::diagnose
