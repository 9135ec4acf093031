// resonance, as the model's own two lightly damped modes moved together: a shaft or coupling
// between two masses made softer (or stiffer) moves its own mode (into the band, where it
// shows as a gain peak above the excited band) and pulls the electromechanical mode with it.
// One change, two modes: a factor in series cannot move the mode the model already has, and a
// series delay or lag took the part the moved modes leave below the band (droopsim's
// softened coupling, docs/droopsim.md). The static gain is kept (a stiffness does not change
// it).
// Plant: none (augmented_model.json carries it).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <optional>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/effects/common.hpp"

namespace rig::diagnose {
namespace {

// A mode of the model counts when its damping ratio is under this (the resonance's bound:
// above it a pole pair hardly peaks and is part of the model's broad shape).
constexpr double kLightDamping = 0.4;
// At 98 % of it the fit stopped at the bound.
constexpr double kAtDampingBound = 0.98 * kLightDamping;
// The second mode is another mode, not the first's near twin (relative frequency apart).
constexpr double kOtherMode = 0.1;

struct Mode {
  double w = 0.0;  // rad/s
  double zeta = 0.0;
  double hz() const { return w / effects::kTwoPi; }
};

// The model's least damped mode (first) and the next least damped one apart from it, both
// under kLightDamping.
std::optional<std::pair<Mode, Mode>> two_modes(const model::TransferFunction& tf) {
  const Eigen::VectorXcd p = tf.poles();
  std::vector<Mode> modes;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (p(i).imag() <= 1e-9 * std::abs(p(i))) continue;
    const Mode m{std::abs(p(i)), -p(i).real() / std::abs(p(i))};
    if (m.zeta < kLightDamping) modes.push_back(m);
  }
  std::sort(modes.begin(), modes.end(),
            [](const Mode& a, const Mode& b) { return a.zeta < b.zeta; });
  if (modes.empty()) return std::nullopt;
  for (std::size_t i = 1; i < modes.size(); ++i)
    if (std::abs(modes[i].w - modes[0].w) > kOtherMode * modes[0].w)
      return std::make_pair(modes[0], modes[i]);
  return std::nullopt;
}

// Ranges for any model's modes (the seeds start at the model's own).
std::vector<ParamSpec> specs(const DataScales& s) {
  return {{"freq_hz", std::max(4.0 / s.duration_s, 1e-3), 0.45 / s.dt_s, true},
          {"zeta", 0.005, kLightDamping, true},
          {"other_freq_hz", std::max(4.0 / s.duration_s, 1e-3), 0.45 / s.dt_s, true},
          {"other_zeta", 0.005, 1.0, true}};
}

std::vector<Params> seeds(const Problem& pr, const Location&) {
  const auto modes = two_modes(pr.tf);
  if (!modes) return {};
  const auto& [a, b] = *modes;
  std::vector<Params> out;
  for (const double r : {0.45, 0.6, 0.8})
    out.push_back({r * b.hz(), b.zeta, (1.0 - 0.05 * (1.0 - r)) * a.hz(), a.zeta});
  return out;
}

// Replaces the pole pairs nearest to `from` by those at `to`, keeping the static gain.
void move(model::TransferFunction& tf, const Mode& from, const Mode& to) {
  const Eigen::VectorXcd p = tf.poles();
  const std::complex<double> old = std::polar(from.w, std::acos(-from.zeta));
  Eigen::Index best = -1;
  for (Eigen::Index i = 0; i < p.size(); ++i)
    if (p(i).imag() > 0.0 && (best < 0 || std::abs(p(i) - old) < std::abs(p(best) - old))) best = i;
  if (best < 0) return;
  Eigen::VectorXcd roots(p.size());
  Eigen::Index k = 0;
  bool dropped_conj = false;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (i == best) continue;
    if (!dropped_conj && std::abs(p(i) - std::conj(p(best))) < 1e-9 * std::abs(p(best))) {
      dropped_conj = true;
      continue;
    }
    roots(k++) = p(i);
  }
  const std::complex<double> disc = std::sqrt(std::complex<double>(to.zeta * to.zeta - 1.0, 0.0));
  roots(k++) = to.w * (-to.zeta + disc);
  roots(k++) = to.w * (-to.zeta - disc);
  // Monic again, the numerator scaled so that the response below both modes is unchanged.
  tf.num *= (to.w * to.w) / (from.w * from.w) / tf.den(0);
  tf.den = poly_from_roots(roots.head(k));
}

void apply(model::TransferFunction& tf, const Params& p) {
  const auto modes = two_modes(tf);
  if (!modes) return;
  const auto& [a, b] = *modes;
  move(tf, b, {effects::kTwoPi * p[0], p[1]});
  move(tf, a, {effects::kTwoPi * p[2], p[3]});
}

// A stiffness change moves every natural frequency of an undamped chain of masses the same
// way (Rayleigh: all down for a softer shaft, all up for a stiffer one). The damping and the
// governor's loop shift the damped modes a little on their own: the pulled mode moving
// against the moved one by more than this fraction of its frequency is no stiffness change.
// On droopsim seeds 1-5 and gensim seed 1 every softened coupling pulled the swing mode the
// same way (2.0-8.5 % down); damper windings from 100 s (seed 4 d057) "moved" the
// coupling's mode down to 8.9 Hz and the swing mode 5.5 % up, and were named a resonance.
constexpr double kAgainstStiffness = 0.02;

// A moved mode whose damping ratio stopped at its bound is the search's stand-in for a broader
// reshaping of the band (as a resonance's, resonance.cpp): droopsim's damper windings behind
// the grid's wander fitted the swing mode re-damped and the coupling's mode "moved" to 9.4 Hz
// at damping 0.4. Nor are two modes that moved against each other (kAgainstStiffness).
bool credible(const AppliedEffect& e, const DataScales& s) {
  if (e.params.size() < 3 || !(e.params[1] < kAtDampingBound)) return false;
  if (!(s.moved_mode_hz > 0.0 && s.pulled_mode_hz > 0.0)) return true;
  const double moved = e.params[0] - s.moved_mode_hz;
  const double pulled = e.params[2] - s.pulled_mode_hz;
  return moved * pulled >= 0.0 || std::abs(pulled) <= kAgainstStiffness * s.pulled_mode_hz;
}

std::string meaning(const AppliedEffect& e, const HypothesisFit&, const Problem& pr) {
  const auto& p = e.params;
  const auto modes = two_modes(pr.tf);
  if (!modes) return fmt::format("the model's modes moved to {:.2f} Hz and {:.2f} Hz", p[0], p[2]);
  const auto& [a, b] = *modes;
  return fmt::format(
      "the model's mode at {:.2f} Hz (damping ratio {:.3f}) has moved to {:.2f} Hz ({:.3f}) and "
      "pulled its mode at {:.2f} Hz ({:.3f}) to {:.2f} Hz ({:.3f}): a {} shaft or coupling "
      "between the masses behind them",
      b.hz(), b.zeta, p[0], p[1], a.hz(), a.zeta, p[2], p[3], p[0] < b.hz() ? "softer" : "stiffer");
}

}  // namespace

bool moved_modes_possible(const model::TransferFunction& tf) { return two_modes(tf).has_value(); }

std::optional<std::pair<double, double>> movable_modes_hz(const model::TransferFunction& tf) {
  const auto modes = two_modes(tf);
  if (!modes) return std::nullopt;
  return std::make_pair(modes->second.hz(), modes->first.hz());
}

double moved_mode_shift(const model::TransferFunction& tf, double freq_hz) {
  const auto modes = two_modes(tf);
  return modes ? std::abs(freq_hz - modes->second.hz()) / modes->second.hz() : INFINITY;
}

const EffectModel kMovedModesEffect{
    .id = Effect::kMovedModes,
    .name = "resonance",
    .kind = EffectKind::kLinear,
    .description =
        "the model's two lightly damped modes moved together (a softer shaft or "
        "coupling between two masses)",
    .parameter_specs = specs,
    .seeds = seeds,
    .apply_linear = apply,
    .explain = meaning,
    .generalises = Effect::kLoadDamping,
    .credible = credible,
};

}  // namespace rig::diagnose
