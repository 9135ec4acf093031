// static_nonlinearity: a static map about the operating point, a polynomial with a kink,
// v = u + c2 u^2 / sigma + c3 u^3 / sigma^2 + k max(u, 0) with sigma = std(u) (blocks.hpp):
// a curvature, and a slope that changes by k at the operating point (a fuel map's kink, a
// valve's characteristic changing there). u is the signal at the effect's place.
// Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <span>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales&) {
  return {{"quadratic_rel", -0.6, 0.6, false},
          {"cubic_rel", -0.3, 0.3, false},
          {"kink_slope_change", -0.6, 1.5, false}};
}

std::vector<Params> seeds(const Problem&, const Location&) {
  return {{0.0, 0.0, 0.0}, {0.1, -0.05, 0.0}, {0.0, 0.0, 0.4}, {0.0, 0.0, -0.3}};
}

Eigen::VectorXd apply(const Problem&, const Params& p, Eigen::VectorXd v) {
  const double sigma = std::sqrt((v.array() - v.mean()).square().mean());
  Eigen::VectorXd out = polynomial(v, p[0], p[1], sigma > 0.0 ? sigma : 1.0);
  return out + p[2] * v.cwiseMax(0.0);
}

double apply_on_error(const Params& p, std::span<const double> e, double sigma, double) {
  const double v = e.back();
  const double s = sigma > 0.0 ? sigma : 1.0;
  return v + p[0] * v * v / s + p[1] * v * v * v / (s * s) + p[2] * std::max(v, 0.0);
}

double step(const Params& p, StepState&, double x, double sigma, double dt_s) {
  return apply_on_error(p, std::span<const double>(&x, 1), sigma, dt_s);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  const auto& p = e.params;
  std::string s = fmt::format(
      "the static gain changes with level: at +1 standard deviation it is {:.2f}, at -1 "
      "it is {:.2f} times the small-signal gain",
      1 + p[0] + p[1] + p[2], 1 - p[0] + p[1]);
  if (std::abs(p[2]) > 0.1)
    s += fmt::format(" (the slope {} by {:.0f} % at the operating point: a kink in the static map)",
                     p[2] > 0 ? "rises" : "falls", 100.0 * std::abs(p[2]));
  return s;
}

}  // namespace

const EffectModel kStaticNonlinearityEffect{
    .id = Effect::kStaticNonlinearity,
    .name = "static_nonlinearity",
    .kind = EffectKind::kInputNonlinearity,
    .description = "a static gain that changes with the input's level",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .apply_on_error = apply_on_error,
    .step = step,
    .explain = meaning,
    .level_shaped = true,
};

}  // namespace rig::diagnose
