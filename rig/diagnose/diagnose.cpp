#include "rig/diagnose/diagnose.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <thread>

#include "rig/diagnose/split.hpp"

namespace rig::diagnose {
namespace {

using thresholds::kDriftMaterialFraction;
using thresholds::kDriftMaterialGainPct;
using thresholds::kDriftMaterialOfLevel;
using thresholds::kOperatingLevelStds;
using thresholds::kPairedInputSingles;
using thresholds::kPairedWithDisturbance;

using Candidate = std::vector<std::vector<AppliedEffect>>;  // starting points of one hypothesis

Candidate single(Effect e, const Problem& pr, const Location& loc) {
  Candidate c;
  for (auto& p : seeds_for(e, pr, loc)) c.push_back({AppliedEffect{e, p}});
  return c;
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

bool has_input_side(const HypothesisFit& h) {
  return std::any_of(h.effects.begin(), h.effects.end(), [](const AppliedEffect& e) {
    return kind_of(e.effect) != EffectKind::kDisturbance;
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

// Pairs of the best input-side singles, and of those with a detected disturbance.
std::vector<Candidate> pair_candidates(const std::vector<HypothesisFit>& singles) {
  std::vector<const HypothesisFit*> inputs, dists;
  for (const auto& h : singles) (has_input_side(h) ? inputs : dists).push_back(&h);
  if (inputs.size() > kPairedInputSingles) inputs.resize(kPairedInputSingles);
  std::vector<Candidate> out;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    for (std::size_t j = i + 1; j < inputs.size(); ++j) {
      const auto lag = [](Effect e) { return e == Effect::kExtraLag || e == Effect::kSensorLag; };
      if (lag(inputs[i]->effects[0].effect) && lag(inputs[j]->effects[0].effect))
        continue;  // twins
      out.push_back({{inputs[i]->effects[0], inputs[j]->effects[0]}});
    }
    for (std::size_t j = 0; j < dists.size() && i < kPairedWithDisturbance; ++j)
      out.push_back({{inputs[i]->effects[0], dists[j]->effects[0]}});
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

// The best hypothesis above min_gain; when the input tests failed, one with an input-side
// effect that adds min_gain to what its disturbance alone explains, unless there is none
// (then a disturbance alone explains it).
int choose_raw(const DiagnoseResult& r, double min_gain) {
  const bool input = r.location.input_mismatch;
  int best_any = -1;
  for (std::size_t i = 0; i < r.hypotheses.size(); ++i) {
    const auto& h = r.hypotheses[i];
    if (h.score < min_gain) break;
    if (immaterial_drift(h, r.problem)) continue;
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
  const int i = choose_raw(r, min_gain);
  if (i < 0) return i;
  const auto& h = r.hypotheses[static_cast<std::size_t>(i)];
  if (h.effects.size() != 2 || h.effects[1].effect != Effect::kDrift) return i;
  bool drift_immaterial = false;
  int single = -1;
  for (std::size_t j = 0; j < r.hypotheses.size(); ++j) {
    const auto& g = r.hypotheses[j];
    if (g.effects.size() != 1) continue;
    if (g.effects[0].effect == Effect::kDrift) drift_immaterial = immaterial_drift(g, r.problem);
    if (g.effects[0].effect == h.effects[0].effect && g.score >= min_gain)
      single = static_cast<int>(j);
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

}  // namespace

const HypothesisFit* DiagnoseResult::chosen() const {
  return chosen_index >= 0 ? &hypotheses[static_cast<std::size_t>(chosen_index)] : nullptr;
}

DiagnoseResult diagnose(const DiagnoseInput& in, const DiagnoseOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  DiagnoseResult r;
  r.problem = prepare_problem(in, &r.blocks, &r.warmup);
  Problem& pr = r.problem;
  // An operating-point step is fitted as a second offset by every model, the baseline too.
  pr.level_shift_at = find_level_shift(pr, pr.y - model_output(pr, {}).yhat);
  const ModelOutput base = model_output(pr, {});
  for (const auto& [name, value] : base.derived)
    if (name == "level_shift") {
      r.level_shift_time_s = static_cast<double>(pr.level_shift_at) * pr.dt_s;
      r.level_shift = value;
    }
  r.baseline_yhat = base.yhat;
  Eigen::ArrayXd used = pr.est_weight + pr.val_weight;
  r.fit_before_pct = weighted_fit_pct(pr.y, base.yhat, used);
  r.validation_fit_before_pct = weighted_fit_pct(pr.y, base.yhat, pr.val_weight);
  r.location = locate(pr, base.yhat);
  gate_to_windows(pr, r.location);
  if (r.location.input_mismatch || r.location.disturbance) {
    std::vector<Candidate> cands;
    for (Effect e : applicable(pr, r.location, o)) cands.push_back(single(e, pr, r.location));
    r.hypotheses = fit_all(pr, cands, base.yhat, o);
    rank(r.hypotheses);
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
