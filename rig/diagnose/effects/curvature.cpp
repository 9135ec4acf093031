// static_nonlinearity, its one-parameter form: a curvature of the static map about the
// operating point, v = u + c2 u^2 / sigma with sigma = std(u) (blocks.hpp). A fuel map or a
// valve characteristic seen at commissioning amplitudes is curved long before it has a kink;
// the full form (static_nonlinearity.cpp) spends two more parameters on a cubic and a kink,
// which behind noise or over part of a record cost more than they buy. u is the signal at
// the effect's place. Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include <cmath>
#include <span>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales&) { return {{"quadratic_rel", -0.6, 0.6, false}}; }

std::vector<Params> seeds(const Problem&, const Location&) { return {{0.0}, {0.1}, {-0.1}}; }

Eigen::VectorXd apply(const Problem&, const Params& p, Eigen::VectorXd v) {
  const double sigma = std::sqrt((v.array() - v.mean()).square().mean());
  return polynomial(v, p[0], 0.0, sigma > 0.0 ? sigma : 1.0);
}

double apply_on_error(const Params& p, std::span<const double> e, double sigma, double) {
  const double v = e.back();
  return v + p[0] * v * v / (sigma > 0.0 ? sigma : 1.0);
}

double step(const Params& p, StepState&, double x, double sigma, double dt_s) {
  return apply_on_error(p, std::span<const double>(&x, 1), sigma, dt_s);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  const double c2 = e.params[0];
  return fmt::format(
      "the static gain changes with level (a curvature of the static map): at +1 standard "
      "deviation it is {:.2f}, at -1 it is {:.2f} times the small-signal gain",
      1 + c2, 1 - c2);
}

}  // namespace

const EffectModel kCurvatureEffect{
    .id = Effect::kCurvature,
    .name = "static_nonlinearity",
    .kind = EffectKind::kInputNonlinearity,
    .description = "a static map curved about the operating point (one parameter)",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_input = apply,
    .apply_on_error = apply_on_error,
    .step = step,
    .explain = meaning,
    .level_shaped = true,
};

}  // namespace rig::diagnose
