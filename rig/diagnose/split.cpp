#include "rig/diagnose/split.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "rig/diagnose/thresholds.hpp"
#include "rig/fra/h1.hpp"
#include "rig/ident/quality.hpp"

namespace rig::diagnose {

using thresholds::kGateMaxCoverage;
using thresholds::kGateMinContiguity;
using thresholds::kGateMinCoverage;
using thresholds::kGateToEnd;
using thresholds::kRolloffHighFrom;
using thresholds::kRolloffHighTo;
using thresholds::kRolloffLowFrom;
using thresholds::kRolloffLowTo;
using thresholds::kSensorLagRolloffRatio;

namespace {

void validate(const DiagnoseInput& in) {
  if (in.u.size() != in.y.size())
    throw std::invalid_argument(fmt::format("input and output differ in length ({} vs {} samples)",
                                            in.u.size(), in.y.size()));
  if (!(in.dt_s > 0.0) || !std::isfinite(in.dt_s))
    throw std::invalid_argument(fmt::format("sample period must be > 0, got {}", in.dt_s));
  for (Eigen::Index k = 0; k < in.u.size(); ++k) {
    if (!std::isfinite(in.u(k)) || !std::isfinite(in.y(k)))
      throw std::invalid_argument(fmt::format("sample {} is not a finite number", k));
  }
  const auto& tf = in.model;
  if (tf.den.size() == 0 || tf.num.size() == 0 || !tf.num.allFinite() || !tf.den.allFinite())
    throw std::invalid_argument("model: empty or non-finite coefficients");
  if (!tf.is_proper())
    throw std::invalid_argument("model: improper (numerator order exceeds denominator order)");
  if (!tf.is_stable())
    throw std::invalid_argument("model: unstable (a pole in the closed right half plane)");
  if (in.output_rc_s && !(*in.output_rc_s > 0.0))
    throw std::invalid_argument("coupling time constant must be > 0");
}

Eigen::Index warmup_samples(const DiagnoseInput& in) {
  const Eigen::VectorXcd p = in.model.poles();
  double slowest = 0.0;
  for (Eigen::Index i = 0; i < p.size(); ++i) slowest = std::max(slowest, -1.0 / p(i).real());
  if (in.output_rc_s) slowest = std::max(slowest, *in.output_rc_s);
  const double t = 4.0 * slowest + in.model.delay_s;
  return std::min<Eigen::Index>(std::llround(t / in.dt_s), in.u.size() / 10);
}

}  // namespace

OutputClip find_output_clip(const Eigen::VectorXd& y) {
  using thresholds::kClipMinSamples, thresholds::kClipPileRatio;
  const ident::ExtremePile p = ident::extreme_pile(y);
  const auto piled = [](Eigen::Index n, Eigen::Index near) {
    return n >= kClipMinSamples && static_cast<double>(n) >= kClipPileRatio * near;
  };
  const bool top = piled(p.at_hi, p.near_hi), bottom = piled(p.at_lo, p.near_lo);
  if (p.hi == p.lo || (!top && !bottom)) return {};
  if (top && (!bottom || p.at_hi >= p.at_lo)) return {+1, p.hi, p.at_hi};
  return {-1, p.lo, p.at_lo};
}

Problem prepare_problem(const DiagnoseInput& in, int* blocks, Eigen::Index* warmup) {
  validate(in);
  Problem pr;
  pr.tf = in.model;
  pr.dt_s = in.dt_s;
  pr.output_rc_s = in.output_rc_s;
  pr.u = in.u.array() - in.u.mean();
  pr.y = in.y.array() - in.y.mean();
  pr.y_level = in.y.mean();
  pr.output_clip = find_output_clip(in.y);
  const Eigen::Index n = in.u.size(), w = warmup_samples(in);
  const int nb = n - w >= 8 * 128 ? 8 : 4;
  const Eigen::Index len = (n - w) / nb;
  if (len < 64)
    throw std::invalid_argument(fmt::format(
        "recording too short to split: {} samples, need at least {} after a warm-up of {}", n,
        nb * 64, w));
  pr.est_weight = Eigen::ArrayXd::Zero(n);
  pr.val_weight = Eigen::ArrayXd::Zero(n);
  for (int b = 0; b < nb; ++b) {
    const Eigen::Index from = w + b * len, to = b + 1 == nb ? n : from + len;
    (b % 2 == 0 ? pr.est_weight : pr.val_weight).segment(from, to - from).setOnes();
  }
  finish_problem(pr);
  if (!(pr.scales.u_std > 0.0))
    throw std::invalid_argument("input is constant: nothing to compare");
  if (!(pr.scales.z_std > 0.0)) throw std::invalid_argument("model output is zero for this input");
  *blocks = nb;
  *warmup = w;
  return pr;
}

void gate_to_windows(Problem& pr, const Location& loc) {
  if (loc.windows.empty()) return;
  const double from = loc.windows.front().from_s, to = loc.windows.back().to_s;
  double covered = 0.0;
  for (const auto& w : loc.windows) covered += w.to_s - w.from_s;
  const double total = pr.scales.duration_s;
  if (covered < kGateMinCoverage * total || covered > kGateMaxCoverage * total ||
      covered < kGateMinContiguity * (to - from))
    return;
  const Eigen::Index n = pr.u.size();
  pr.active_from = std::clamp<Eigen::Index>(std::llround(from / pr.dt_s), 0, n);
  // A span reaching the last whole window runs to the end (the remainder is shorter).
  pr.active_to =
      to >= kGateToEnd * total ? n : std::clamp<Eigen::Index>(std::llround(to / pr.dt_s), 0, n);
}

namespace {

double band_mean(const fra::CrossSpectra& s, double lo, double hi) {
  double sum = 0.0;
  int k = 0;
  for (Eigen::Index i = 1; i < s.freq_hz.size(); ++i)
    if (s.freq_hz(i) >= lo && s.freq_hz(i) <= hi) sum += s.gyy(i), ++k;
  return k >= 2 ? sum / k : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

void add_sensor_lag_twin(const Problem& pr, std::vector<HypothesisFit>& hs, const FitOptions& fit) {
  auto it = std::find_if(hs.begin(), hs.end(), [](const HypothesisFit& h) {
    return h.effects.size() == 1 && h.effects[0].effect == Effect::kExtraLag &&
           h.effects[0].place == Place::kInput;  // a transducer's lag is outside the loop
  });
  if (it == hs.end()) return;
  const double fc = 1.0 / (2.0 * std::numbers::pi * it->effects[0].params[0]);
  fra::WelchOptions wo;
  wo.segment_length = welch_segment(pr.u.size());
  const Eigen::VectorXd r = pr.y - it->yhat;
  const fra::CrossSpectra s = fra::welch_cross_spectra(pr.u, r, pr.dt_s, wo);
  const double ratio =
      band_mean(s, kRolloffHighFrom * fc, std::min(kRolloffHighTo * fc, 0.45 / pr.dt_s)) /
      band_mean(s, kRolloffLowFrom * fc, kRolloffLowTo * fc);
  HypothesisFit twin = *it;
  twin.effects[0].effect = Effect::kSensorLag;
  it->derived.emplace_back("noise_rolloff_ratio", ratio);
  twin.derived.emplace_back("noise_rolloff_ratio", ratio);
  const bool sensor = std::isfinite(ratio) && ratio < kSensorLagRolloffRatio;
  (sensor ? it->score : twin.score) -= fit.penalty_pct_per_parameter;
  hs.push_back(std::move(twin));
}

bool explains(const Problem& pr, const HypothesisFit& h, const Location& loc) {
  for (Effect d : {Effect::kPeriodicDisturbance, Effect::kDrift}) {
    const bool detected = d == Effect::kDrift ? loc.dist.drift : loc.dist.periodic;
    const bool included = std::any_of(h.effects.begin(), h.effects.end(),
                                      [d](const AppliedEffect& e) { return e.effect == d; });
    if (detected && !included) return false;
  }
  // A disturbance alone leaves the amplitude tests' finding unexplained: the output depended
  // on the input's level, sign or direction (an effect from half-way behind the grid's
  // wander, which the cross-correlation over the whole record no longer sees).
  const bool disturbance_only = std::none_of(
      h.effects.begin(), h.effects.end(),
      [](const AppliedEffect& e) { return kind_of(e.effect) != EffectKind::kDisturbance; });
  if (disturbance_only && !loc.amp.two_level_input && (loc.amp.fails())) return false;
  if (h.yhat.size() == 0) return true;
  Eigen::Index from = 0;
  while (from < pr.y.size() && pr.est_weight(from) + pr.val_weight(from) <= 0.0) ++from;
  const Eigen::VectorXd r = (pr.y - h.yhat).tail(pr.y.size() - from);
  const auto lags = static_cast<Eigen::Index>(loc.tests.auto_corr.size()) - 1;
  return residual_tests(r, pr.u.tail(pr.y.size() - from), pr.dt_s, lags).independent;
}

}  // namespace rig::diagnose
