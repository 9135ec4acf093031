#include "rig/diagnose/diagnose.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/split.hpp"
#include "rig/diagnose/timing.hpp"

namespace rig::diagnose {
namespace {

using thresholds::kDirectionEvidenceZ;
using thresholds::kDominantDisturbanceGainPct;
using thresholds::kDriftMaterialFraction;
using thresholds::kDriftMaterialGainPct;
using thresholds::kDriftMaterialOfLevel;
using thresholds::kNestedMarginPct;
using thresholds::kNonlinearOverLinearPct;
using thresholds::kOperatingLevelStds;
using thresholds::kPairedInputSingles;
using thresholds::kPairedWithDisturbance;
using thresholds::kRefinedSingles;
using thresholds::kScreenEvaluations;
using thresholds::kScreenMaxDecimation;
using thresholds::kScreenMinSamples;
using thresholds::kScreenOversampling;

using Candidate = std::vector<std::vector<AppliedEffect>>;  // starting points of one hypothesis

// One effect's hypotheses: an input-side nonlinearity at each place it can sit
// (placement.hpp), any other effect once.
std::vector<Candidate> singles(Effect e, const Problem& pr, const Location& loc) {
  if (kind_of(e) != EffectKind::kInputNonlinearity)
    return {placed_starts(e, Place::kInput, pr, loc)};
  std::vector<Candidate> out;
  for (Place place : kAllPlaces) {
    if (place == Place::kInLoop && !in_loop_possible(pr.tf)) continue;
    if (place == Place::kFeedback && !effect_model(e).in_feedback) continue;
    out.push_back(placed_starts(e, place, pr, loc));
  }
  return out;
}

std::vector<HypothesisFit> fit_all(const Problem& pr, const std::vector<Candidate>& cands,
                                   const Eigen::VectorXd& base, const DiagnoseOptions& o) {
  std::vector<HypothesisFit> out(cands.size());
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < cands.size(); i = next++)
      out[i] = fit_hypothesis(pr, cands[i], base, o.fit);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, o.threads); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  return out;
}

void rank(std::vector<HypothesisFit>& hs);

// The screen's decimation: keep kScreenOversampling samples per period of the highest
// excited frequency, at most kScreenMaxDecimation, none for a short record.
int screen_decimation(const Problem& pr) {
  if (pr.u.size() < kScreenMinSamples) return 1;
  double band_hz = 0.0;  // the input's band: its rate over its rms, as a frequency
  band_hz = pr.scales.u_rate_std / (2.0 * std::numbers::pi * std::max(pr.scales.u_std, 1e-300));
  const int f = static_cast<int>(std::floor(1.0 / (pr.dt_s * kScreenOversampling *
                                                   std::max(band_hz, 1e-9))));
  return std::clamp(f, 1, kScreenMaxDecimation);
}

// Every f-th sample of the problem (the input and output as recorded, the weights and
// spans with them), its derived fields rebuilt.
Problem decimated(const Problem& pr, int f) {
  if (f <= 1) return pr;
  Problem out = pr;
  const Eigen::Index n = (pr.u.size() + f - 1) / f;
  auto pick = [&](const auto& x) {
    std::decay_t<decltype(x)> y(n);
    for (Eigen::Index i = 0; i < n; ++i) y(i) = x(i * f);
    return y;
  };
  out.u = pick(pr.u);
  out.y = pick(pr.y);
  out.est_weight = pick(pr.est_weight);
  out.val_weight = pick(pr.val_weight);
  out.dt_s = pr.dt_s * f;
  out.active_from = pr.active_from / f;
  out.active_to = pr.active_to < 0 ? -1 : (pr.active_to + f - 1) / f;
  out.level_shift_at = pr.level_shift_at < 0 ? -1 : pr.level_shift_at / f;
  finish_problem(out);
  return out;
}

// Every single hypothesis is fitted with a short search (a screen), and the best few are
// then searched in full from where the screen stopped (thresholds.hpp).
std::vector<HypothesisFit> screen_and_refine(const Problem& pr, const std::vector<Candidate>& cands,
                                             const Eigen::VectorXd& base,
                                             const DiagnoseOptions& o) {
  DiagnoseOptions screen = o;
  screen.fit.max_evaluations = std::min(o.fit.max_evaluations, kScreenEvaluations);
  const Problem coarse = decimated(pr, screen_decimation(pr));
  std::vector<HypothesisFit> hs =
      fit_all(coarse, cands, model_output(coarse, {}).yhat, screen);
  rank(hs);
  const std::size_t k = std::min(hs.size(), kRefinedSingles);
  std::vector<Candidate> best;
  for (std::size_t i = 0; i < k; ++i) best.push_back({hs[i].effects});
  std::vector<HypothesisFit> refined = fit_all(pr, best, base, o);
  for (std::size_t i = 0; i < hs.size(); ++i) {
    const int screened = hs[i].evaluations;
    hs[i] = i < k ? std::move(refined[i]) : score_hypothesis(pr, hs[i].effects, base, o.fit);
    hs[i].evaluations += screened;
    hs[i].screened_only = i >= k;
  }
  rank(hs);
  return hs;
}

bool has_input_side(const HypothesisFit& h) {
  return std::any_of(h.effects.begin(), h.effects.end(), [](const AppliedEffect& e) {
    return kind_of(e.effect) != EffectKind::kDisturbance;
  });
}

// Every effect of h that needs the direction test's evidence has it (thresholds.hpp). The
// test regresses on the input's direction of motion: it says nothing of a loop in an output
// feedback (a hysteretic spring follows the output's motion), which is exempt.
bool direction_evidenced(const HypothesisFit& h, const Location& loc) {
  return std::none_of(h.effects.begin(), h.effects.end(), [&](const AppliedEffect& e) {
    return effect_model(e.effect).needs_direction_evidence && e.place != Place::kFeedback &&
           std::abs(loc.amp.direction_z) < kDirectionEvidenceZ;
  });
}

bool has_nonlinearity(const HypothesisFit& h) {
  return std::any_of(h.effects.begin(), h.effects.end(), [](const AppliedEffect& e) {
    return kind_of(e.effect) == EffectKind::kInputNonlinearity;
  });
}

std::vector<Effect> applicable(const Problem& pr, const Location& loc, const DiagnoseOptions& o) {
  std::vector<Effect> out;
  const auto& pool =
      o.effects.empty() ? std::vector<Effect>(kAllEffects.begin(), kAllEffects.end()) : o.effects;
  for (Effect e : pool) {
    if (e == Effect::kSensorLag) continue;  // the twin of extra_lag, told apart afterwards
    if (e == Effect::kLoadDamping && !dominant_mode(pr.tf)) continue;
    if (e == Effect::kPeriodicDisturbance && !loc.dist.periodic) continue;
    if (e == Effect::kDrift && !loc.dist.drift) continue;
    if (kind_of(e) != EffectKind::kDisturbance && !loc.input_mismatch) continue;
    out.push_back(e);
  }
  return out;
}

// Pairs of the best input-side singles (the best place of each effect), and of those with a
// detected disturbance; every input-side effect with a disturbance that dominates the
// residual (its single's score, fitted without it, says little then).
std::vector<Candidate> pair_candidates(const std::vector<HypothesisFit>& singles) {
  std::vector<const HypothesisFit*> inputs, dists;  // singles are ranked
  for (const auto& h : singles) {
    if (!has_input_side(h)) {
      dists.push_back(&h);
      continue;
    }
    const bool seen = std::any_of(inputs.begin(), inputs.end(), [&](const HypothesisFit* g) {
      return g->effects[0].effect == h.effects[0].effect;
    });
    if (!seen) inputs.push_back(&h);
  }
  const bool dominant = !dists.empty() && dists.front()->score >= kDominantDisturbanceGainPct;
  const auto lag = [](Effect e) { return e == Effect::kExtraLag || e == Effect::kSensorLag; };
  std::vector<Candidate> out;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const AppliedEffect& a = inputs[i]->effects[0];
    for (std::size_t j = i + 1; j < std::min(inputs.size(), kPairedInputSingles); ++j) {
      const AppliedEffect& b = inputs[j]->effects[0];
      if (i >= kPairedInputSingles || (lag(a.effect) && lag(b.effect))) continue;  // twins
      if (a.place == b.place && (a.place == Place::kInLoop || a.place == Place::kFeedback))
        continue;  // one front lag, one feedback path
      out.push_back({{a, b}});
    }
    for (std::size_t j = 0; j < dists.size(); ++j)
      if ((i < kPairedWithDisturbance) || (dominant && j == 0))
        out.push_back({{a, dists[j]->effects[0]}});
  }
  return out;
}

void rank(std::vector<HypothesisFit>& hs) {
  std::stable_sort(hs.begin(), hs.end(), [](const HypothesisFit& a, const HypothesisFit& b) {
    return a.score > b.score;
  });
}

// The score of the same hypothesis without its input-side effects (0 when it has no
// disturbance): what a pair's input-side half must add to.
double disturbance_part_score(const std::vector<HypothesisFit>& hs, const HypothesisFit& h) {
  double best = 0.0;
  for (const auto& e : h.effects) {
    if (kind_of(e.effect) != EffectKind::kDisturbance) continue;
    for (const auto& g : hs)
      if (g.effects.size() == 1 && g.effects[0].effect == e.effect) best = std::max(best, g.score);
  }
  return best;
}

// A drift alone is material when it is large against the input-driven response or the
// operating level, or when modelling it raises the validation fit enough (thresholds.hpp).
bool immaterial_drift(const HypothesisFit& h, const Problem& pr) {
  if (h.effects.size() != 1 || h.effects[0].effect != Effect::kDrift) return false;
  double rms = 0.0;
  for (const auto& [name, value] : h.derived)
    if (name == "drift_rms") rms = value;
  const double y_std = std::sqrt(pr.y.squaredNorm() / std::max<double>(1.0, pr.y.size()));
  const double level = std::abs(pr.y_level);
  if (level > kOperatingLevelStds * y_std && rms < kDriftMaterialOfLevel * level) return true;
  if (h.validation_fit_after - h.validation_fit_before >= kDriftMaterialGainPct) return false;
  return rms < kDriftMaterialFraction * pr.scales.z_std;
}

// A dead time of at most half a sample alone is the sampling convention (timing.hpp).
bool sampling_convention_only(const HypothesisFit& h, const Problem& pr) {
  return h.effects.size() == 1 && h.effects[0].effect == Effect::kDeadTime &&
         std::abs(h.effects[0].params[0]) <= 0.5 * pr.dt_s;
}

// The best hypothesis above min_gain; when the input tests failed, one with an input-side
// effect that adds min_gain to what its disturbance alone explains, unless there is none
// (then a disturbance alone explains it).
int choose_raw(const DiagnoseResult& r, double min_gain, bool linear_only = false) {
  const bool input = r.location.input_mismatch;
  int best_any = -1;
  for (std::size_t i = 0; i < r.hypotheses.size(); ++i) {
    const auto& h = r.hypotheses[i];
    if (h.score < min_gain) break;
    if (linear_only && has_nonlinearity(h)) continue;
    if (!direction_evidenced(h, r.location)) continue;
    if (immaterial_drift(h, r.problem) || sampling_convention_only(h, r.problem)) continue;
    if (best_any < 0) best_any = static_cast<int>(i);
    if (!input) return static_cast<int>(i);
    if (has_input_side(h) && h.score - disturbance_part_score(r.hypotheses, h) >= min_gain)
      return static_cast<int>(i);
  }
  return best_any;
}

// A pair "effect + drift" whose drift alone is immaterial is reported as the effect alone
// when that single scores min_gain too: the augmented model should not carry the set's
// normal wander as a change.
int choose(const DiagnoseResult& r, double min_gain) {
  int i = choose_raw(r, min_gain);
  if (i < 0) return i;
  // An effect that contains a simpler one must beat it by a margin (thresholds.hpp).
  if (const auto& h = r.hypotheses[static_cast<std::size_t>(i)]; h.effects.size() == 1) {
    if (const auto simpler = effect_model(h.effects[0].effect).generalises) {
      for (std::size_t j = 0; j < r.hypotheses.size(); ++j) {
        const auto& g = r.hypotheses[j];
        if (g.effects.size() == 1 && g.effects[0].effect == *simpler) {
          if (g.score >= h.score - kNestedMarginPct) i = static_cast<int>(j);
          break;  // ranked: the simpler effect's best place
        }
      }
    }
  }
  // A nonlinearity must beat the best linear explanation by a margin (thresholds.hpp).
  if (has_nonlinearity(r.hypotheses[static_cast<std::size_t>(i)])) {
    const int j = choose_raw(r, min_gain, true);
    if (j >= 0 && r.hypotheses[static_cast<std::size_t>(j)].score >=
                      r.hypotheses[static_cast<std::size_t>(i)].score - kNonlinearOverLinearPct)
      i = j;
  }
  const auto& h = r.hypotheses[static_cast<std::size_t>(i)];
  if (h.effects.size() != 2 || h.effects[1].effect != Effect::kDrift) return i;
  bool drift_immaterial = false;
  int single = -1;
  for (std::size_t j = 0; j < r.hypotheses.size(); ++j) {
    const auto& g = r.hypotheses[j];
    if (g.effects.size() != 1) continue;
    if (g.effects[0].effect == Effect::kDrift) drift_immaterial = immaterial_drift(g, r.problem);
    if (single < 0 && g.effects[0].effect == h.effects[0].effect && g.score >= min_gain)
      single = static_cast<int>(j);  // ranked: the effect's best place
  }
  return drift_immaterial && single >= 0 ? single : i;
}

// The verdict word of a chosen hypothesis: its input-side effect (the first listed, pairs
// keep the better single first), else its disturbance.
std::string verdict_of(const HypothesisFit& h) {
  for (const auto& e : h.effects)
    if (kind_of(e.effect) != EffectKind::kDisturbance) return to_string(e.effect);
  return to_string(h.effects.front().effect);
}

// The baseline's output (with an operating-point step found in the residual, fitted as a
// second offset by every model, the baseline too) and the location of its residual.
ModelOutput locate_baseline(Problem& pr, DiagnoseResult& r) {
  pr.level_shift_at = find_level_shift(pr, pr.y - model_output(pr, {}).yhat);
  ModelOutput base = model_output(pr, {});
  std::optional<double> step;
  for (const auto& [name, value] : base.derived)
    if (name == "level_shift") step = value;
  if (step) {
    r.level_shift_time_s = static_cast<double>(pr.level_shift_at) * pr.dt_s;
    r.level_shift = *step;
    // The step is taken out of the recording, so that every fit measures the dynamics: a
    // gain change with the level in it steps the level by (g - 1) x level, which would
    // otherwise dominate the variance every fit percentage is taken of.
    const Eigen::Index n = pr.y.size();
    pr.y.tail(n - pr.level_shift_at).array() -= *step;
    pr.level_shift_at = -1;
    base = model_output(pr, {});
  }
  r.baseline_yhat = base.yhat;
  const Eigen::ArrayXd used = pr.est_weight + pr.val_weight;
  r.fit_before_pct = weighted_fit_pct(pr.y, base.yhat, used);
  r.validation_fit_before_pct = weighted_fit_pct(pr.y, base.yhat, pr.val_weight);
  r.location = locate(pr, base.yhat);
  return base;
}

// When the verdict reports an effect alone although its pair with the (immaterial) drift
// ranks higher, the pair's estimate of the effect, fitted with the wander modelled, is kept
// if it scores at least as well alone: the single's own fit lets the wander bend it.
void keep_pair_estimate(DiagnoseResult& r, const Eigen::VectorXd& base, const DiagnoseOptions& o) {
  HypothesisFit& h = r.hypotheses[static_cast<std::size_t>(r.chosen_index)];
  if (h.effects.size() != 1) return;
  for (const auto& g : r.hypotheses) {
    if (&g == &h) return;  // ranked below the chosen: no pair above it
    if (g.effects.size() == 2 && g.effects[1].effect == Effect::kDrift &&
        g.effects[0].effect == h.effects[0].effect && g.effects[0].place == h.effects[0].place) {
      HypothesisFit alone = score_hypothesis(r.problem, {g.effects[0]}, base, o.fit);
      if (alone.score >= h.score) {
        alone.evaluations = h.evaluations + 1;
        h = std::move(alone);
      }
      return;
    }
  }
}

}  // namespace

const HypothesisFit* DiagnoseResult::chosen() const {
  return chosen_index >= 0 ? &hypotheses[static_cast<std::size_t>(chosen_index)] : nullptr;
}

DiagnoseResult diagnose(const DiagnoseInput& in, const DiagnoseOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  DiagnoseResult r;
  r.problem = prepare_problem(in, &r.blocks, &r.warmup);
  Problem& pr = r.problem;
  // The sampling convention (timing.hpp): when the baseline shifted by at most half a sample
  // explains the recording, that is the answer (none); otherwise the effects are fitted
  // against the model as given, so that the shift takes nothing of theirs.
  Problem shifted = pr;
  if (const double delta = absorb_timing_nuisance(shifted); delta != 0.0) {
    DiagnoseResult s;
    locate_baseline(shifted, s);
    if (!s.location.input_mismatch && !s.location.disturbance) {
      pr = std::move(shifted);
      r.timing_nuisance_s = delta;
    }
  }
  const ModelOutput base = locate_baseline(pr, r);
  gate_to_windows(pr, r.location);
  if (r.location.input_mismatch || r.location.disturbance) {
    std::vector<Candidate> cands;
    for (Effect e : applicable(pr, r.location, o))
      for (auto& c : singles(e, pr, r.location)) cands.push_back(std::move(c));
    r.hypotheses = screen_and_refine(pr, cands, base.yhat, o);
    refine_onsets(pr, r.hypotheses, base.yhat, o.fit);
    add_sensor_lag_twin(pr, r.hypotheses, o.fit);
    rank(r.hypotheses);
    if (o.try_pairs && !r.hypotheses.empty() && !explains(pr, r.hypotheses.front(), r.location)) {
      auto pairs = fit_all(pr, pair_candidates(r.hypotheses), base.yhat, o);
      for (auto& h : pairs) r.hypotheses.push_back(std::move(h));
      rank(r.hypotheses);
    }
  }
  r.chosen_index = choose(r, o.min_gain_pct);
  // A verdict's parameters come from a full search, also when the procedure chose one the
  // screen ranked below the refined few.
  if (r.chosen_index >= 0 && r.chosen()->screened_only) {
    HypothesisFit& h = r.hypotheses[static_cast<std::size_t>(r.chosen_index)];
    const int screened = h.evaluations;
    h = fit_hypothesis(pr, {h.effects}, base.yhat, o.fit);
    h.evaluations += screened;
  }
  if (r.chosen_index >= 0) keep_pair_estimate(r, base.yhat, o);
  // A disturbance alone that no hypothesis makes worth its parameters is not material.
  if (!r.location.input_mismatch && (!r.location.disturbance || !r.chosen())) {
    r.verdict = "none";
  } else {
    r.verdict = r.chosen() ? verdict_of(*r.chosen()) : "unexplained";
  }
  r.explanation = explain(r);
  r.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace rig::diagnose
