// dead_time: a dead time the model lacks (or has too much of), extra_delay_s added to the
// baseline's. Seeded from the slope of the phase error. Also tried on the governor's error
// (placement.hpp, "error") and inside the governor's loop with its feedback fitted
// ("governor_loop"): a delay inside the loop (a fuel transport delay) changes the loop's
// dynamics, not only the output's timing; it cannot be negative there.
// Plant: engine.dead_time_s = Td0 + extra_delay_s, Td0 the effective fuel dead time
// (dead_time_s if > 0, else 30/N + 60/(n N)).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <span>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"
#include "rig/diagnose/governor_loop.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"extra_delay_s", -s.delay_s, std::min(2.0, 0.05 * s.duration_s), false}};
}

std::vector<Params> seeds(const Problem&, const Location& loc) {
  const FrequencyLocation& f = loc.freq;
  return {{f.delay_from_phase_s}, {0.5 * f.delay_from_phase_s + 0.01}};
}

void apply(model::TransferFunction& tf, const Params& p) {
  tf.delay_s = std::max(0.0, tf.delay_s + p[0]);
}

// On the error: e delayed by p[0] >= 0, interpolated linearly between samples (e held at its
// first value before the record).
double apply_on_error(const Params& p, std::span<const double> e, double, double dt_s) {
  const double delay = std::max(0.0, p[0]) / dt_s;
  const auto whole = static_cast<std::ptrdiff_t>(std::floor(delay));
  const double frac = delay - static_cast<double>(whole);
  const auto at = [&](std::ptrdiff_t back) {
    const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(e.size()) - 1 - back;
    return e[static_cast<std::size_t>(std::max<std::ptrdiff_t>(i, 0))];
  };
  return (1.0 - frac) * at(whole) + frac * at(whole + 1);
}

// Inside the governor's loop with its feedback fitted: the delay's Pade approximant.
void loop_factor(const Params& p, Eigen::VectorXd& num, Eigen::VectorXd& den) {
  pade_delay(p[0], num, den);
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  if (e.place == Place::kError || e.place == Place::kGovernorLoop)
    return fmt::format(
        "a dead time of {:.0f} ms is missing inside the governor's loop (a transport delay "
        "such as the fuel's: it slows the loop's response, not only the output's timing)",
        1e3 * std::max(0.0, p[0]));
  return p[0] >= 0 ? fmt::format(
                         "a dead time of {:.0f} ms is missing (the recording's is {:.0f} ms, "
                         "the model's {:.0f} ms)",
                         1e3 * p[0], 1e3 * (pr.tf.delay_s + p[0]), 1e3 * pr.tf.delay_s)
                   : fmt::format("the model's dead time is {:.0f} ms too long", -1e3 * p[0]);
}

double effective_dead_time_s(const PlantTarget& p) {
  const double td = p.param("engine.dead_time_s");
  if (td > 0.0) return td;
  const double n = p.param("engine.rpm");
  return 30.0 / n + 60.0 / (p.param("engine.cylinders") * n);
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  const double td0 = effective_dead_time_s(m);
  m.set("engine.dead_time_s", std::max(td0 + p[0], 1e-4), name,
        fmt::format("fuel dead time {:.4g} s + extra_delay_s {:.4g} s", td0, p[0]));
}

// Inside the loop a delay is positive (the approximant of a negative one is no delay). It
// may be shorter than a sample: unlike a shift of the output (the sampling convention,
// timing.hpp) it changes the loop's dynamics, which the record resolves.
bool credible(const AppliedEffect& e, const DataScales&) {
  return e.place != Place::kGovernorLoop || e.params[0] > 0.0;
}

}  // namespace

const EffectModel kDeadTimeEffect{
    .id = Effect::kDeadTime,
    .name = "dead_time",
    .kind = EffectKind::kLinear,
    .description = "a transport delay the model lacks or has too much of",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_linear = apply,
    .apply_on_error = apply_on_error,
    .loop_factor = loop_factor,
    .explain = meaning,
    .map_to_plant = to_plant,
    .credible = credible,
};

}  // namespace rig::diagnose
