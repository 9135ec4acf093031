#include "rig/diagnose/augmented_model.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "rig/diagnose/blocks.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::diagnose {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) out(i++) = x;
  return out;
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

void apply_linear(model::TransferFunction& tf, const AppliedEffect& e) {
  const auto& p = e.params;
  switch (e.effect) {
    case Effect::kDeadTime:
      tf.delay_s = std::max(0.0, tf.delay_s + p[0]);
      break;
    case Effect::kExtraLag:
    case Effect::kSensorLag:
      tf.den = poly_multiply(tf.den, vec({p[0], 1.0}));
      break;
    case Effect::kResonance: {
      // (s^2 + 2 zeta r w s + w^2) / (s^2 + 2 zeta w s + w^2): unity away from w, a peak
      // of r at w (a notch when r < 1). Scaled by 1/w^2 for conditioning.
      const double w = kTwoPi * p[0], zeta = p[1], r = p[2];
      tf.num = poly_multiply(tf.num, vec({1.0 / (w * w), 2.0 * zeta * r / w, 1.0}));
      tf.den = poly_multiply(tf.den, vec({1.0 / (w * w), 2.0 * zeta / w, 1.0}));
      break;
    }
    case Effect::kAcCoupling:
      tf.num = poly_multiply(tf.num, vec({p[0], 0.0}));
      tf.den = poly_multiply(tf.den, vec({p[0], 1.0}));
      break;
    case Effect::kLoadDamping:
      set_mode_damping(tf, p[0]);
      break;
    case Effect::kGainChange:
      tf.num *= p[0];
      break;
    default:
      break;
  }
}

Eigen::VectorXd apply_input(const Problem& pr, const AppliedEffect& e, Eigen::VectorXd v) {
  const auto& p = e.params;
  switch (e.effect) {
    case Effect::kDeadband:
      return deadband(v, p[0]);
    case Effect::kBacklash:
      return backlash(v, p[0]);
    case Effect::kSaturation:
      return p.size() > 2 ? saturate_in_loop(v, -p[1], p[0], p[2], pr.dt_s)
                          : saturate(v, -p[1], p[0]);
    case Effect::kRateLimit:
      return p.size() > 1 ? rate_limit_in_loop(v, p[0], p[1], pr.dt_s)
                          : rate_limit(v, p[0], pr.dt_s);
    case Effect::kStaticNonlinearity:
      return polynomial(v, p[0], p[1], pr.scales.u_std);
    default:
      return v;
  }
}

// Output feedback of nonlinear_stiffness (cubic, kappa = relative incremental stiffness
// change 3 k3 sigma^2 K at one standard deviation sigma of the output, K the static gain)
// and coulomb_friction (Fc tanh(dz / eps), eps = 5 % of the rate's standard deviation).
OutputFeedback feedback_of(const Problem& pr, std::span<const AppliedEffect> effects) {
  double k3 = 0.0, fc = 0.0;
  const double sz = std::max(pr.scales.z_std, 1e-300);
  const double eps = 0.05 * std::max(pr.scales.z_rate_std, 1e-300);
  for (const auto& e : effects) {
    if (e.effect == Effect::kNonlinearStiffness)
      k3 = e.params[0] / (3.0 * sz * sz * pr.scales.dc_gain);
    if (e.effect == Effect::kCoulombFriction) fc = e.params[0];
  }
  return [=](double z, double dz) { return k3 * z * z * z + fc * std::tanh(dz / eps); };
}

}  // namespace

model::TransferFunction augmented_tf(const model::TransferFunction& tf,
                                     std::span<const AppliedEffect> effects) {
  model::TransferFunction out = tf;
  for (const auto& e : effects) apply_linear(out, e);
  return out;
}

double weighted_fit_pct(const Eigen::VectorXd& y, const Eigen::VectorXd& yhat,
                        const Eigen::ArrayXd& w) {
  const double sw = w.sum();
  if (!(sw > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double mean = (w * y.array()).sum() / sw;
  const double num = (w * (y - yhat).array().square()).sum();
  const double den = (w * (y.array() - mean).square()).sum();
  return 100.0 * (1.0 - std::sqrt(num / den));
}

std::optional<std::pair<double, double>> dominant_mode(const model::TransferFunction& tf) {
  const Eigen::VectorXcd p = tf.poles();
  std::optional<std::pair<double, double>> best;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (p(i).imag() <= 1e-9 * std::abs(p(i))) continue;
    const double zeta = -p(i).real() / std::abs(p(i));
    if (!best || zeta < best->second) best = std::make_pair(std::abs(p(i)) / kTwoPi, zeta);
  }
  return best;
}

void finish_problem(Problem& pr) {
  const Eigen::Index n = pr.u.size();
  pr.baseline_z = model::simulate(pr.tf, pr.u, pr.dt_s);
  auto std_of = [](const Eigen::VectorXd& x) {
    return std::sqrt((x.array() - x.mean()).square().mean());
  };
  DataScales& s = pr.scales;
  s.dt_s = pr.dt_s;
  s.duration_s = static_cast<double>(n) * pr.dt_s;
  s.u_std = std_of(pr.u);
  s.u_rate_std = n > 1 ? std_of((pr.u.tail(n - 1) - pr.u.head(n - 1)) / pr.dt_s) : 1.0;
  s.z_std = std_of(pr.baseline_z);
  if (s.z_std > 0.0)
    s.z_peak_ratio = (pr.baseline_z.array() - pr.baseline_z.mean()).abs().maxCoeff() / s.z_std;
  s.z_rate_std =
      n > 1 ? std_of((pr.baseline_z.tail(n - 1) - pr.baseline_z.head(n - 1)) / pr.dt_s) : 1.0;
  s.delay_s = pr.tf.delay_s;
  s.dc_gain = pr.tf.dc_gain();
  if (!std::isfinite(s.dc_gain) || std::abs(s.dc_gain) < 1e-12) {
    double peak = 0.0;
    for (double f = 1e-3; f < 0.5 / pr.dt_s; f *= 1.05)
      peak = std::max(peak, std::abs(pr.tf.response(f)));
    s.dc_gain = peak > 0.0 ? peak : 1.0;
  }
  if (pr.active_to < 0 || pr.active_to > n) pr.active_to = n;
}

ModelOutput model_output(const Problem& pr, std::span<const AppliedEffect> effects) {
  ModelOutput out;
  const DataScales& s = pr.scales;
  bool input_side = false, feedback = false;
  Eigen::VectorXd v = pr.u;
  for (const auto& e : effects) {
    if (e.params.size() != parameter_specs(e.effect, s).size())
      throw std::invalid_argument(std::string("model_output: wrong parameter count for ") +
                                  to_string(e.effect));
    const EffectKind kind = kind_of(e.effect);
    input_side = input_side || kind != EffectKind::kDisturbance;
    feedback = feedback || kind == EffectKind::kFeedback;
    if (kind == EffectKind::kInputNonlinearity) v = apply_input(pr, e, std::move(v));
  }
  out.tf = augmented_tf(pr.tf, effects);
  Eigen::VectorXd z;
  if (!input_side) {
    z = pr.baseline_z;
  } else {
    z = feedback ? simulate_with_feedback(out.tf, v, pr.dt_s, feedback_of(pr, effects))
                 : model::simulate(out.tf, v, pr.dt_s);
    const Eigen::Index n = z.size();
    if (pr.active_from > 0) z.head(pr.active_from) = pr.baseline_z.head(pr.active_from);
    if (pr.active_to < n) z.tail(n - pr.active_to) = pr.baseline_z.tail(n - pr.active_to);
  }
  if (pr.output_rc_s) z = signal::ac_couple(z, pr.dt_s, *pr.output_rc_s);
  // Offset (and the periodic disturbance's cosine and sine) by weighted least squares.
  const AppliedEffect* periodic = nullptr;
  const AppliedEffect* drift = nullptr;
  for (const auto& e : effects) {
    if (e.effect == Effect::kPeriodicDisturbance) periodic = &e;
    if (e.effect == Effect::kDrift) drift = &e;
  }
  const Eigen::Index n = z.size();
  const bool shift = pr.level_shift_at > 0 && pr.level_shift_at < n;
  Eigen::MatrixXd x(n, (periodic ? 3 : 1) + (shift ? 1 : 0));
  x.col(0).setOnes();
  if (shift) {
    x.col(x.cols() - 1).head(pr.level_shift_at).setZero();
    x.col(x.cols() - 1).tail(n - pr.level_shift_at).setOnes();
  }
  if (periodic) {
    const Eigen::ArrayXd t =
        Eigen::ArrayXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * pr.dt_s;
    x.col(1) = (kTwoPi * periodic->params[0] * t).cos().matrix();
    x.col(2) = (kTwoPi * periodic->params[0] * t).sin().matrix();
  }
  const Eigen::VectorXd sw = pr.est_weight.sqrt().matrix();
  const Eigen::VectorXd beta =
      (sw.asDiagonal() * x).colPivHouseholderQr().solve(sw.asDiagonal() * (pr.y - z));
  out.yhat = z + x * beta;
  if (shift) out.derived.emplace_back("level_shift", beta(x.cols() - 1));
  if (periodic) {
    out.derived.emplace_back("amplitude", std::hypot(beta(1), beta(2)));
    out.derived.emplace_back("phase_deg", std::atan2(-beta(2), beta(1)) * 180.0 / std::numbers::pi);
  }
  if (drift) {
    const Eigen::VectorXd d = smooth_zero_phase(pr.y - out.yhat, drift->params[0], pr.dt_s);
    out.yhat += d;
    out.derived.emplace_back("drift_rms", std::sqrt(d.array().square().mean()));
  }
  return out;
}

}  // namespace rig::diagnose
