// static_nonlinearity: a static polynomial about the operating point,
// v = u + c2 u^2 / sigma + c3 u^3 / sigma^2 with sigma = std(u) (blocks.hpp).
// Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales&) {
  return {{"quadratic_rel", -0.6, 0.6, false}, {"cubic_rel", -0.3, 0.3, false}};
}

std::vector<Params> seeds(const Problem&, const Location&) { return {{0.0, 0.0}, {0.1, -0.05}}; }

Eigen::VectorXd apply(const Problem& pr, const Params& p, Eigen::VectorXd v) {
  return polynomial(v, p[0], p[1], pr.scales.u_std);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem&) {
  const auto& p = e.params;
  return fmt::format(
      "the static gain changes with level: at +1 standard deviation it is {:.2f}, at -1 "
      "it is {:.2f} times the small-signal gain",
      1 + p[0] + p[1], 1 - p[0] + p[1]);
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
    .explain = meaning,
};

}  // namespace rig::diagnose
