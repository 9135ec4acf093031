#include "rig/diagnose/augmented_model.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <tuple>

#include "rig/diagnose/blocks.hpp"
#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/error_loop.hpp"
#include "rig/diagnose/governor_loop.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::diagnose {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A linear effect changes the transfer function: in series, or inside the governor's loop
// (governor_loop.hpp); but on the governor's error (a dead time inside the loop), where the
// error loop applies it instead.
void apply_linear(model::TransferFunction& tf, const AppliedEffect& e) {
  if (on_error(e.place)) return;
  const EffectModel& m = effect_model(e.effect);
  if (e.place == Place::kGovernorLoop) {
    if (!m.loop_factor)
      throw std::invalid_argument(std::string("no form in the loop for ") + m.name);
    Eigen::VectorXd nf, df;
    m.loop_factor(e.params, nf, df);
    tf = close_governor_loop(tf, nf, df, e.place_params);
    return;
  }
  if (const auto apply = m.apply_linear) apply(tf, e.params);
}

Eigen::VectorXd apply_input(const Problem& pr, const AppliedEffect& e, Eigen::VectorXd v) {
  if (const auto apply = effect_model(e.effect).apply_input)
    return apply(pr, e.params, std::move(v));
  return v;
}

// The output feedback of the feedback effects (their terms: effect_registry.hpp).
OutputFeedback feedback_of(const Problem& pr, std::span<const AppliedEffect> effects) {
  FeedbackTerms t;
  for (const auto& e : effects)
    if (const auto terms = effect_model(e.effect).feedback) terms(pr, e.params, t);
  return [=](double z, double dz) {
    return t.cubic * z * z * z + t.friction * std::tanh(dz / t.friction_eps);
  };
}

// The output z plus an offset (the level shift's, and the disturbances' regressors) fitted
// by weighted least squares on the estimation samples, then the disturbances' corrections.
void fit_output(const Problem& pr, std::span<const AppliedEffect> effects, const Eigen::VectorXd& z,
                ModelOutput& out) {
  std::vector<const AppliedEffect*> fitted;
  Eigen::Index extra = 0;
  for (const auto& e : effects)
    if (const int c = effect_model(e.effect).regressor_columns; c > 0)
      fitted.push_back(&e), extra += c;
  const Eigen::Index n = z.size();
  const bool shift = pr.level_shift_at > 0 && pr.level_shift_at < n;
  Eigen::MatrixXd x(n, 1 + extra + (shift ? 1 : 0));
  x.col(0).setOnes();
  if (shift) {
    x.col(x.cols() - 1).head(pr.level_shift_at).setZero();
    x.col(x.cols() - 1).tail(n - pr.level_shift_at).setOnes();
  }
  Eigen::Index col = 1;
  for (const AppliedEffect* e : fitted) {
    const EffectModel& m = effect_model(e->effect);
    m.regressors(pr, e->params, x.middleCols(col, m.regressor_columns));
    col += m.regressor_columns;
  }
  // A disturbance alone acts on the hypothesis's span as an input-side effect does (a line
  // that starts during the record: a misfire, a ripple from 100 s); beside an input-side
  // effect the span is that effect's and the disturbance runs through the record.
  const bool alone = std::none_of(effects.begin(), effects.end(), [](const AppliedEffect& e) {
    return kind_of(e.effect) != EffectKind::kDisturbance;
  });
  if (alone && extra > 0) {
    const Eigen::Index to = pr.active_to < 0 || pr.active_to > n ? n : pr.active_to;
    if (pr.active_from > 0) x.block(0, 1, pr.active_from, extra).setZero();
    if (to < n) x.block(to, 1, n - to, extra).setZero();
  }
  const OutputClip& clip = pr.output_clip;
  const double clip_y = clip.level - pr.y_level;  // in pr.y's units
  Eigen::VectorXd sw = pr.est_weight.sqrt().matrix();
  if (clip.side != 0)  // the clipped samples say only that the output was beyond the clip
    sw = ((pr.y.array() - clip_y).abs() > 1e-9 * std::abs(clip_y) + 1e-300).select(sw.array(), 0.0);
  const Eigen::VectorXd beta =
      (sw.asDiagonal() * x).colPivHouseholderQr().solve(sw.asDiagonal() * (pr.y - z));
  out.yhat = z + x * beta;
  if (shift) out.derived.emplace_back("level_shift", beta(x.cols() - 1));
  col = 1;
  for (const AppliedEffect* e : fitted) {
    const EffectModel& m = effect_model(e->effect);
    m.from_coefficients(beta.segment(col, m.regressor_columns), out.derived);
    col += m.regressor_columns;
  }
  for (const auto& e : effects)
    if (const auto after = effect_model(e.effect).after_fit)
      after(pr, e.params, out.yhat, out.derived);
  if (clip.side > 0) out.yhat = out.yhat.cwiseMin(clip_y);
  if (clip.side < 0) out.yhat = out.yhat.cwiseMax(clip_y);
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
  if (const auto modes = movable_modes_hz(pr.tf))
    std::tie(s.moved_mode_hz, s.pulled_mode_hz) = *modes;
  s.dc_gain = pr.tf.dc_gain();
  if (!std::isfinite(s.dc_gain) || std::abs(s.dc_gain) < 1e-12) {
    double peak = 0.0;
    for (double f = 1e-3; f < 0.5 / pr.dt_s; f *= 1.05)
      peak = std::max(peak, std::abs(pr.tf.response(f)));
    s.dc_gain = peak > 0.0 ? peak : 1.0;
  }
  if (pr.active_to < 0 || pr.active_to > n) pr.active_to = n;
}

namespace {

// The output of the linear part for the input v, through the in-loop nonlinearity `loop`
// when there is one (placement.hpp), with the feedback effects' loop when there are any.
Eigen::VectorXd linear_output(const Problem& pr, std::span<const AppliedEffect> effects,
                              const model::TransferFunction& tf, const AppliedEffect* loop,
                              Eigen::VectorXd v, bool feedback) {
  model::TransferFunction g = tf;
  if (loop) {
    const double lag_s = loop->place_params.at(0);
    const Eigen::VectorXd w = front_signal(v, lag_s, pr.dt_s);
    const double k = in_loop_scale(pr, w);
    v = apply_input(pr, *loop, k * w) / k;
    g = rest_after_front(tf, lag_s);
  }
  return feedback ? simulate_with_feedback(g, v, pr.dt_s, feedback_of(pr, effects))
                  : model::simulate(g, v, pr.dt_s);
}

// The feedback-placed nonlinearity (placement.hpp): v - c (y' - N(y')), y' = z / G0, solved
// by fixed-point iteration over the whole record (thresholds.hpp); NaN when it does not
// settle (the fit then rejects the point).
Eigen::VectorXd close_feedback(const Problem& pr, std::span<const AppliedEffect> effects,
                               const model::TransferFunction& tf, const AppliedEffect* loop,
                               const AppliedEffect& fb, const Eigen::VectorXd& v, bool feedback,
                               Eigen::VectorXd z) {
  const double g0 = pr.scales.dc_gain, c = fb.place_params.at(0);
  for (int pass = 0; pass < thresholds::kFeedbackPasses; ++pass) {
    const Eigen::VectorXd yp = z / g0;
    const Eigen::VectorXd f = c * (yp - apply_input(pr, fb, yp));
    const Eigen::VectorXd next = linear_output(pr, effects, tf, loop, v - f, feedback);
    const double change = (next - z).norm(), size = std::max(next.norm(), 1e-300);
    z = thresholds::kFeedbackRelaxation * next + (1.0 - thresholds::kFeedbackRelaxation) * z;
    if (!z.allFinite()) break;
    if (change <= thresholds::kFeedbackTolerance * size) return z;
  }
  z.setConstant(std::numeric_limits<double>::quiet_NaN());
  return z;
}

// The output-placed nonlinearities act on z in the bias's static scale.
void apply_at_output(const Problem& pr, std::span<const AppliedEffect> effects,
                     Eigen::VectorXd& z) {
  const double g0 = pr.scales.dc_gain;
  for (const auto& e : effects)
    if (kind_of(e.effect) == EffectKind::kInputNonlinearity && e.place == Place::kOutput)
      z = g0 * apply_input(pr, e, z / g0);
}

// The fitted feedback of an effect's place (the unity one where it has none).
LoopFeedback loop_feedback_of(const AppliedEffect& e) {
  return feedback_fitted(e.place) ? loop_feedback(e.place_params) : LoopFeedback{};
}

// N of the error loop's effect (error_loop.hpp): on the error itself, or after the PI.
std::function<double(std::span<const double>)> error_effect(const Problem& pr,
                                                            const AppliedEffect& err) {
  const EffectModel& m = effect_model(err.effect);
  const LoopFeedback h = loop_feedback_of(err);
  const LoopFeedback* fb = feedback_fitted(err.place) ? &h : nullptr;
  if (after_pi(err.place)) {
    const PiGovernor gov = pi_governor(err.place_params);
    const PiSignal a = pi_signal(pr, gov, fb);
    // The signal's own rms, as the place's seeds and bounds have it (problem_at).
    const double sigma = std::sqrt((a.a.array() - a.a.mean()).square().mean());
    const auto step = m.step;
    return pi_loop_on_error([step, &p = err.params, sigma, dt_s = pr.dt_s](
                                StepState& s, double x) { return step(p, s, x, sigma, dt_s); },
                            a.k, gov, pr.dt_s);
  }
  const Eigen::VectorXd e0 = linear_error(pr, fb);
  const double sigma = std::sqrt((e0.array() - e0.mean()).square().mean());
  return [on_error = m.apply_on_error, &p = err.params, sigma,
          dt_s = pr.dt_s](std::span<const double> e) { return on_error(p, e, sigma, dt_s); };
}

// A governor loop closed with a fitted feedback that makes it unstable (the recording's
// plant is not: the point is outside the hypothesis), or that could not be closed: an effect
// before it left the model no static gain (an AC coupling: G0 = 0, so G / G0 is no loop's
// and the closed loop's numerator vanishes, its denominator too when the loop is unchanged).
bool unstable_loop(std::span<const AppliedEffect> effects, const model::TransferFunction& tf) {
  if (std::none_of(effects.begin(), effects.end(),
                   [](const AppliedEffect& e) { return e.place == Place::kGovernorLoop; }))
    return false;
  const auto vanishes = [](const Eigen::VectorXd& p) {
    return p.size() == 0 || !p.allFinite() || p.cwiseAbs().maxCoeff() == 0.0;
  };
  const bool degenerate = vanishes(tf.num) || vanishes(tf.den);
  return degenerate || !tf.is_stable();
}

}  // namespace

ModelOutput model_output(const Problem& pr, std::span<const AppliedEffect> effects) {
  std::vector<AppliedEffect> shared;  // one governor, one feedback (governor_loop.hpp)
  if (shared_feedback(effects)) {
    shared.assign(effects.begin(), effects.end());
    share_feedback(shared);
    effects = shared;
  }
  ModelOutput out;
  const DataScales& s = pr.scales;
  bool input_side = false, feedback = false;
  const AppliedEffect *loop = nullptr, *fb = nullptr, *err = nullptr;
  Eigen::VectorXd v = pr.u;
  for (const auto& e : effects) {
    if (e.params.size() != parameter_specs(e.effect, s).size() ||
        e.place_params.size() != place_specs(e.place, s).size())
      throw std::invalid_argument(std::string("model_output: wrong parameter count for ") +
                                  to_string(e.effect));
    const EffectKind kind = kind_of(e.effect);
    input_side = input_side || kind != EffectKind::kDisturbance;
    feedback = feedback || kind == EffectKind::kFeedback;
    if (in_error_loop(e.place)) {
      if (err) throw std::invalid_argument("model_output: two effects in the error loop");
      if (on_error(e.place) ? !effect_model(e.effect).apply_on_error : !effect_model(e.effect).step)
        throw std::invalid_argument(std::string("model_output: no form on the error for ") +
                                    to_string(e.effect));
      err = &e;
    }
    if (kind != EffectKind::kInputNonlinearity) continue;
    if (e.place == Place::kInput) v = apply_input(pr, e, std::move(v));
    if (e.place == Place::kInLoop) {
      if (loop) throw std::invalid_argument("model_output: two effects in the loop");
      loop = &e;
    }
    if (e.place == Place::kFeedback) {
      if (fb) throw std::invalid_argument("model_output: two effects in the feedback");
      fb = &e;
    }
  }
  // The error loop's correction goes through the linear part only (error_loop.hpp).
  if (err && (loop || fb || feedback))
    throw std::invalid_argument("model_output: the error place with another loop");
  out.tf = augmented_tf(pr.tf, effects);
  Eigen::VectorXd z;
  if (!input_side) {
    z = pr.baseline_z;
  } else if (unstable_loop(effects, out.tf)) {  // explains nothing: the fit rejects the point
    z = Eigen::VectorXd::Constant(pr.u.size(), std::numeric_limits<double>::quiet_NaN());
  } else {
    z = linear_output(pr, effects, out.tf, loop, v, feedback);
    if (fb) z = close_feedback(pr, effects, out.tf, loop, *fb, v, feedback, std::move(z));
    // The loop tracks the bias as the input-placed effects left it (v).
    if (err) {
      const LoopFeedback h = loop_feedback_of(*err);
      z = close_error_loop(out.tf, v, z, s.dc_gain, pr.dt_s, error_effect(pr, *err),
                           feedback_fitted(err->place) ? &h : nullptr);
    }
    apply_at_output(pr, effects, z);
    const Eigen::Index n = z.size();
    if (pr.active_from > 0) z.head(pr.active_from) = pr.baseline_z.head(pr.active_from);
    if (pr.active_to < n) z.tail(n - pr.active_to) = pr.baseline_z.tail(n - pr.active_to);
  }
  if (pr.output_rc_s) z = signal::ac_couple(z, pr.dt_s, *pr.output_rc_s);
  fit_output(pr, effects, z, out);
  return out;
}

}  // namespace rig::diagnose
