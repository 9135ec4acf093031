// load_damping: the least damped mode of the baseline with another damping ratio (its
// natural frequency, and so the static gain, kept).
// Plant: alt.d_pu *= zeta / zeta0 (the swing mode's damping ratio is about proportional to
// D; zeta0 of the baseline's least damped pole pair).
#include <fmt/format.h>

#include <cmath>
#include <complex>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

std::vector<ParamSpec> specs(const DataScales&) { return {{"zeta", 0.005, 1.5, true}}; }

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const auto mode = dominant_mode(pr.tf);
  const double z = mode ? mode->second : 0.1;
  return {{z * 0.6}, {z * 1.6}};
}

// Replaces the least damped complex pole pair's damping ratio; wn (and so the static gain,
// since the pair contributes wn^2 to a_0) is kept.
void set_mode_damping(model::TransferFunction& tf, double zeta) {
  const Eigen::VectorXcd p = tf.poles();
  Eigen::Index best = -1;
  double best_zeta = 2.0;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (p(i).imag() <= 1e-9 * std::abs(p(i))) continue;
    const double z = -p(i).real() / std::abs(p(i));
    if (z < best_zeta) best_zeta = z, best = i;
  }
  if (best < 0) return;
  const double wn = std::abs(p(best));
  Eigen::VectorXcd roots(p.size());
  Eigen::Index k = 0;
  bool dropped_conj = false;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (i == best) continue;
    if (!dropped_conj && std::abs(p(i) - std::conj(p(best))) < 1e-9 * wn) {
      dropped_conj = true;
      continue;
    }
    roots(k++) = p(i);
  }
  const std::complex<double> disc = std::sqrt(std::complex<double>(zeta * zeta - 1.0, 0.0));
  roots(k++) = wn * (-zeta + disc);
  roots(k++) = wn * (-zeta - disc);
  tf.den = tf.den(0) * poly_from_roots(roots.head(k));
}

void apply(model::TransferFunction& tf, const Params& p) { set_mode_damping(tf, p[0]); }

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto m = dominant_mode(pr.tf);
  return fmt::format(
      "the mode at {:.2f} Hz is damped with a ratio of {:.3f}, not the model's {:.3f}",
      m ? m->first : 0.0, e.params[0], m ? m->second : 0.0);
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  const auto mode = dominant_mode(c.baseline);
  if (!mode || !(mode->second > 0.0)) {
    m.note("load_damping: the baseline has no damped pole pair; alt.d_pu left unchanged");
    return;
  }
  m.set("alt.d_pu", m.current("alt.d_pu") * p[0] / mode->second, name,
        fmt::format("D x zeta {:.4g} / baseline zeta {:.4g} ({:.3g} Hz mode)", p[0], mode->second,
                    mode->first));
}

}  // namespace

const EffectModel kLoadDampingEffect{
    .id = Effect::kLoadDamping,
    .name = "load_damping",
    .kind = EffectKind::kLinear,
    .description = "the dominant mode is damped differently from the model",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_linear = apply,
    .explain = meaning,
    .map_to_plant = to_plant,
};

}  // namespace rig::diagnose
