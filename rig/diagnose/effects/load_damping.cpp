// load_damping: the least damped mode of the baseline with another damping ratio (its
// natural frequency, and so the static gain, kept). Damper windings act on the electrical
// power itself (P_e = K_s delta + D slip), so a power reading's response carries a real zero
// at K_s w_b / D = w_n / (2 zeta_D), zeta_D the part of the mode's damping ratio D gives:
// when the model has its zero, D's change moves it too (a damping that is mechanical, in
// the swing equation only, leaves no zero and the mode alone is re-damped).
// Plant: alt.d_pu *= the change of D (zeta / zeta0 when the model has no damper zero).
#include <fmt/format.h>

#include <algorithm>
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

// A real zero this close (a factor either way) to w_n / (2 zeta_0) is the damper's: on
// droopsim (damper windings in P_e) it sits 1.17x above; plantsim's and gensim's damping is
// mechanical and their nearest real zeros are 1.7x and 3.7x away (a shaft, a transducer).
constexpr double kDamperZeroSpan = 1.4;
// D after the change is at least this share of D before (the zero stays finite).
constexpr double kMinDamperFactor = 0.05;

struct Mode {
  Eigen::Index index = -1;  // of the pole with positive imaginary part
  double wn = 0.0;          // rad/s
  double zeta = 0.0;
};

Mode least_damped(const Eigen::VectorXcd& p) {
  Mode m;
  double best_zeta = 2.0;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (p(i).imag() <= 1e-9 * std::abs(p(i))) continue;
    const double z = -p(i).real() / std::abs(p(i));
    if (z < best_zeta) best_zeta = z, m = {i, std::abs(p(i)), z};
  }
  return m;
}

// The index of the damper's real zero in z, or -1.
Eigen::Index damper_zero(const Eigen::VectorXcd& z, const Mode& m) {
  const double target = m.wn / (2.0 * m.zeta);
  Eigen::Index best = -1;
  double best_dist = std::log(kDamperZeroSpan);
  for (Eigen::Index i = 0; i < z.size(); ++i) {
    if (std::abs(z(i).imag()) > 1e-9 * std::abs(z(i)) || !(z(i).real() < 0.0)) continue;
    const double d = std::abs(std::log(-z(i).real() / target));
    if (d < best_dist) best_dist = d, best = i;
  }
  return best;
}

// D after over D before for the mode's new damping ratio (zeta_D = w_n / (2 z) its share),
// 1 when the model has no damper zero.
double damper_factor(const model::TransferFunction& tf, double zeta) {
  const Mode m = least_damped(tf.poles());
  if (m.index < 0 || !(m.zeta > 0.0)) return 1.0;
  const Eigen::VectorXcd z = tf.zeros();
  const Eigen::Index k = damper_zero(z, m);
  if (k < 0) return 1.0;
  const double zeta_d = m.wn / (2.0 * -z(k).real());
  return std::max(kMinDamperFactor, 1.0 + (zeta - m.zeta) / zeta_d);
}

// Moves the damper's zero to z / factor, the static gain kept.
void move_damper_zero(model::TransferFunction& tf, const Mode& m, double factor) {
  Eigen::VectorXcd z = tf.zeros();
  const Eigen::Index k = damper_zero(z, m);
  if (k < 0 || factor == 1.0) return;
  Eigen::Index lead = 0;
  while (lead < tf.num.size() - 1 && tf.num(lead) == 0.0) ++lead;
  z(k) /= factor;
  tf.num = tf.num(lead) * factor * poly_from_roots(z);
}

// Replaces the least damped complex pole pair's damping ratio; wn (and so the static gain,
// since the pair contributes wn^2 to a_0) is kept. The damper's zero, if any, moves with it.
void set_mode_damping(model::TransferFunction& tf, double zeta) {
  const Eigen::VectorXcd p = tf.poles();
  const Mode m = least_damped(p);
  if (m.index < 0) return;
  move_damper_zero(tf, m, damper_factor(tf, zeta));
  const double wn = m.wn;
  Eigen::VectorXcd roots(p.size());
  Eigen::Index k = 0;
  bool dropped_conj = false;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (i == m.index) continue;
    if (!dropped_conj && std::abs(p(i) - std::conj(p(m.index))) < 1e-9 * wn) {
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
  const std::string text =
      fmt::format("the mode at {:.2f} Hz is damped with a ratio of {:.3f}, not the model's {:.3f}",
                  m ? m->first : 0.0, e.params[0], m ? m->second : 0.0);
  const double factor = damper_factor(pr.tf, e.params[0]);
  if (factor == 1.0) return text;
  return fmt::format(
      "{} (damper windings: their damping x{:.2f}, which also moves the power's damping zero)",
      text, factor);
}

void to_plant(const PlantContext& c, PlantTarget& m) {
  const std::string name = to_string(c.effect.effect);
  const auto& p = c.effect.params;
  const auto mode = dominant_mode(c.baseline);
  if (!mode || !(mode->second > 0.0)) {
    m.note("load_damping: the baseline has no damped pole pair; alt.d_pu left unchanged");
    return;
  }
  const double factor = damper_factor(c.baseline, p[0]);
  if (factor != 1.0) {
    m.set("alt.d_pu", m.current("alt.d_pu") * factor, name,
          fmt::format("D x {:.4g} (zeta {:.4g} against the baseline's {:.4g}, the damper's zero "
                      "moved with it)",
                      factor, p[0], mode->second));
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
