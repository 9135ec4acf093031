#include "rig/diagnose/search.hpp"

#include <algorithm>
#include <cmath>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/governor_loop.hpp"
#include "rig/diagnose/pairs.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/screen.hpp"
#include "rig/diagnose/split.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {
namespace {

using thresholds::kDominantDisturbanceGainPct;
using thresholds::kRefinedBehindDisturbance;
using thresholds::kRefinedDominantPlaces;
using thresholds::kRefinedForwardPairs;
using thresholds::kRefinedLoopPairs;

// One effect's hypotheses: an input-side nonlinearity at each place it can sit
// (placement.hpp), a linear effect with a form on the error or in the governor's loop at the
// input and there, any other effect once.
std::vector<Candidate> singles_of(Effect e, const Problem& pr, const Location& loc) {
  if (kind_of(e) == EffectKind::kLinear) {
    const EffectModel& m = effect_model(e);
    std::vector<Candidate> out{placed_starts(e, Place::kInput, pr, loc)};
    if (m.apply_on_error) out.push_back(placed_starts(e, Place::kError, pr, loc));
    if (m.loop_factor && governor_loop_possible(pr.tf))
      out.push_back(placed_starts(e, Place::kGovernorLoop, pr, loc));
    return out;
  }
  if (kind_of(e) != EffectKind::kInputNonlinearity)
    return {placed_starts(e, Place::kInput, pr, loc)};
  std::vector<Candidate> out;
  for (Place place : kAllPlaces) {
    if (place == Place::kInLoop && !in_loop_possible(pr.tf)) continue;
    if (place == Place::kFeedback && !effect_model(e).in_feedback) continue;
    if (on_error(place) && !effect_model(e).apply_on_error) continue;
    if (after_pi(place) && !effect_model(e).step) continue;
    if (effect_model(e).tried_at && !effect_model(e).tried_at(place)) continue;
    if (feedback_fitted(place) && !governor_loop_possible(pr.tf)) continue;
    // On a two-level input any map of the bias itself acts as a linear one: a static map
    // as a gain and an offset, a play or a slew limit the same on every (equal) step.
    if (place == Place::kInput && loc.amp.two_level_input) continue;
    out.push_back(placed_starts(e, place, pr, loc));
  }
  return out;
}

bool gated(const Problem& pr, const HypothesisFit& h) {
  return h.active_from != pr.active_from ||
         (h.active_to < 0 ? pr.y.size() : h.active_to) != pr.active_to;
}

bool same_effects(const HypothesisFit& a, const HypothesisFit& b) {
  return a.effects.size() == b.effects.size() &&
         std::equal(a.effects.begin(), a.effects.end(), b.effects.begin(),
                    [](const AppliedEffect& x, const AppliedEffect& y) {
                      return x.effect == y.effect && x.place == y.place;
                    });
}

// When an onset was found for one of the best hypotheses (onset.cpp), every input-side
// hypothesis is searched again on that span, so that all compete on the same footing: the
// onset search refits only the few best, ranked on the whole record, where an effect present
// in half of it is matched as well by a lag or a gain as by its own form.
void research_at_onset(const Problem& pr, const std::vector<Candidate>& cands,
                       std::vector<HypothesisFit>& hs, const Eigen::VectorXd& base,
                       const DiagnoseOptions& o) {
  const auto onset = std::find_if(hs.begin(), hs.end(), [&](const HypothesisFit& h) {
    return has_input_side(h) && gated(pr, h);
  });
  if (onset == hs.end()) return;
  const Problem at = spanned(pr, *onset);
  std::vector<Candidate> inputs;
  for (const auto& c : cands)
    if (kind_of(c.front().front().effect) != EffectKind::kDisturbance) inputs.push_back(c);
  for (auto& g : screen_and_refine(at, inputs, base, o)) {
    auto h = std::find_if(hs.begin(), hs.end(),
                          [&](const HypothesisFit& x) { return same_effects(x, g); });
    if (h == hs.end()) continue;
    const int evaluations = h->evaluations;
    if (g.score > h->score) *h = std::move(g);
    h->evaluations += evaluations;
  }
  rank(hs);
}

// The effects of the pool (all, or the options' list) that can be tried on this record:
// input-side ones when the input tests failed, or the output was clipped, or `behind` (a
// dominant disturbance may have hidden them, behind_disturbance below).
std::vector<Effect> applicable(const Problem& pr, const Location& loc, const DiagnoseOptions& o,
                               bool behind = false) {
  std::vector<Effect> out;
  const auto& pool =
      o.effects.empty() ? std::vector<Effect>(kAllEffects.begin(), kAllEffects.end()) : o.effects;
  for (Effect e : pool) {
    if (e == Effect::kSensorLag) continue;  // the twin of extra_lag, told apart afterwards
    if (e == Effect::kLoadDamping && !dominant_mode(pr.tf)) continue;
    if (e == Effect::kMovedModes && !moved_modes_possible(pr.tf)) continue;
    if (e == Effect::kPeriodicDisturbance && !loc.dist.periodic) continue;
    if (e == Effect::kDrift && !loc.dist.drift) continue;
    if (kind_of(e) != EffectKind::kDisturbance && !loc.input_mismatch && loc.clip.side == 0 &&
        !behind)
      continue;
    out.push_back(e);
  }
  return out;
}

// A line and a drift both detected: the line fitted beside the drift (its single, fitted
// without it, is ranked by the wander; a torque ripple behind the grid's wander).
std::vector<HypothesisFit> both_disturbances(const Problem& pr,
                                             const std::vector<HypothesisFit>& singles,
                                             const Eigen::VectorXd& base,
                                             const DiagnoseOptions& o) {
  const auto single = [&](Effect e) {
    return std::find_if(singles.begin(), singles.end(), [e](const HypothesisFit& h) {
      return h.effects.size() == 1 && h.effects[0].effect == e;
    });
  };
  const auto line = single(Effect::kPeriodicDisturbance), drift = single(Effect::kDrift);
  if (line == singles.end() || drift == singles.end()) return {};
  return fit_all(pr, {{{line->effects[0], drift->effects[0]}}}, base, o);
}

// When the input tests passed but a disturbance dominates the residual, its wander widened
// their bounds and may hide an input-side effect (a rack stop behind the grid's wander): every
// input-side effect at each place is paired with that disturbance, seeded from what it
// leaves, screened, and the best few searched in full. The verdict asks such a pair to add
// kUnseenInputGainPct to the disturbance alone (verdict.cpp).
std::vector<HypothesisFit> behind_disturbance(const Problem& pr, const Location& loc,
                                              const std::vector<HypothesisFit>& singles,
                                              const Eigen::VectorXd& base,
                                              const DiagnoseOptions& o) {
  if (loc.input_mismatch || loc.clip.side != 0 || !o.try_pairs) return {};
  const auto dist = std::find_if(singles.begin(), singles.end(),
                                 [](const HypothesisFit& h) { return !has_input_side(h); });
  if (dist == singles.end() || dist->score < kDominantDisturbanceGainPct) return {};
  const Location left = locate(pr, dist->yhat);
  std::vector<Candidate> cands;
  for (Effect e : applicable(pr, loc, o, true)) {
    if (kind_of(e) == EffectKind::kDisturbance) continue;
    for (const Candidate& c : singles_of(e, pr, left)) {
      Candidate paired;
      for (const auto& start : c) paired.push_back({start.front(), dist->effects[0]});
      cands.push_back(std::move(paired));
    }
  }
  std::vector<HypothesisFit> pairs =
      screen_and_refine(pr, cands, base, o, kRefinedBehindDisturbance);
  refine_onsets_beside(pr, pairs, *dist, base, o.fit);
  return pairs;
}

}  // namespace

// The problem with the effects acting on h's span only (an onset found for h).
Problem spanned(const Problem& pr, const HypothesisFit& h) {
  Problem out = pr;
  out.active_from = h.active_from;
  out.active_to = h.active_to < 0 ? pr.y.size() : h.active_to;
  return out;
}

namespace {

// An effect found from an onset (onset.cpp) beside each detected disturbance, on the same
// span, from both singles' fits: its pair with the disturbance over the whole record is the
// effect diluted by the part without it (a transducer's gain change from half-way behind the
// grid's wander, droopsim seed 2 d017, was named `drift`).
std::vector<HypothesisFit> gated_with_disturbances(const Problem& pr,
                                                   const std::vector<HypothesisFit>& singles,
                                                   const Eigen::VectorXd& base,
                                                   const DiagnoseOptions& o) {
  // By span (the onset re-search gates every input-side single at one): screened, the best
  // few searched in full, as the forward pairs are.
  std::vector<std::pair<const HypothesisFit*, std::vector<Candidate>>> spans;
  for (const auto& h : singles) {
    if (h.effects.size() != 1 || !has_input_side(h) || !gated(pr, h)) continue;
    auto at = std::find_if(spans.begin(), spans.end(), [&](const auto& sp) {
      return sp.first->active_from == h.active_from && sp.first->active_to == h.active_to;
    });
    if (at == spans.end()) at = spans.insert(spans.end(), {&h, {}});
    for (const auto& d : singles)
      if (d.effects.size() == 1 && !has_input_side(d))
        at->second.push_back({{h.effects[0], d.effects[0]}});
  }
  std::vector<HypothesisFit> out;
  for (const auto& [h, cands] : spans)
    for (auto& g : screen_and_refine(spanned(pr, *h), cands, base, o, kRefinedForwardPairs))
      out.push_back(std::move(g));
  return out;
}

// Every applicable single (the input-side ones also when `blind`) screened and the best
// searched in full, onsets, the sensor-lag twin; ranked.
std::vector<HypothesisFit> search_singles(const Problem& pr, const Location& loc,
                                          const Eigen::VectorXd& base, const DiagnoseOptions& o,
                                          bool blind) {
  std::vector<Candidate> cands;
  for (Effect e : applicable(pr, loc, o, blind))
    for (auto& c : singles_of(e, pr, loc)) cands.push_back(std::move(c));
  std::vector<HypothesisFit> hs = screen_and_refine(pr, cands, base, o);
  refine_onsets(pr, hs, base, o.fit);
  research_at_onset(pr, cands, hs, base, o);
  add_sensor_lag_twin(pr, hs, o.fit);
  rank(hs);
  return hs;
}

}  // namespace

std::vector<HypothesisFit> blind_search(const Problem& pr, const Location& loc,
                                        const Eigen::VectorXd& base, const DiagnoseOptions& o) {
  return search_singles(pr, loc, base, o, true);
}

namespace {

// The location's direction test shows a play beyond any lag (thresholds.hpp,
// kDirectionBeyondLagZ) that the best single, without a play or a hysteresis loop, does not
// hold: its residual may pass the cross-correlation, the play's pair with it is still
// searched (droopsim s2 d074: a transducer's lag and a linkage play, the lag in the loop
// alone explaining the correlation).
bool leaves_play(const HypothesisFit& best, const Location& loc) {
  const bool has_play = std::any_of(best.effects.begin(), best.effects.end(), [](const auto& e) {
    return effect_model(e.effect).needs_direction_evidence;
  });
  return !has_play && !loc.amp.two_level_input &&
         loc.amp.direction_beyond_lag_z <= -thresholds::kDirectionBeyondLagZ;
}

// A disturbance alone leaves a failed input test unexplained: the test saw the residual
// depend on the input, which no drift or line does, even when the disturbance's own residual
// then passes the cross-correlation test (the wander widened its bound). Its pairs with the
// input-side effects are searched (gensim seed 5 g074, a rack stop behind a 20 kW drift: the
// drift alone scored 52.3 points, no pair was fitted and an AC coupling alone at 3.7 was
// named).
bool leaves_input_test(const HypothesisFit& best, const Location& loc) {
  return loc.input_mismatch && !has_input_side(best);
}

}  // namespace

std::vector<HypothesisFit> search_hypotheses(const Problem& pr, const Location& loc,
                                             const Eigen::VectorXd& base,
                                             const DiagnoseOptions& o) {
  std::vector<HypothesisFit> hs = search_singles(pr, loc, base, o, false);
  // Added last: the pair searches below take the singles' disturbances one at a time.
  std::vector<HypothesisFit> lines = both_disturbances(pr, hs, base, o);
  const auto done = [&](std::vector<HypothesisFit> more) {
    for (auto* add : {&more, &lines})
      for (auto& h : *add) hs.push_back(std::move(h));
    rank(hs);
    return hs;
  };
  // Input tests passed: the pairs with the disturbance are the only ones.
  if (auto behind = behind_disturbance(pr, loc, hs, base, o); !behind.empty())
    return done(std::move(behind));
  if (!o.try_pairs || hs.empty()) return done({});
  // Pairs are searched unless the best single and the best that could be a verdict both
  // explain the residual, and no stand-in (a fit no verdict can name, verdict.cpp
  // could_be_verdict) scores a pair's margin above the latter. A stand-in that explains says
  // nothing of whether the credible shape needs a second effect, and one ahead by that much
  // shows it may (a resonance at its damping bound for a damping change beside a
  // transducer's lag, gensim g075).
  const auto best = std::find_if(hs.begin(), hs.end(), [&](const HypothesisFit& h) {
    return could_be_verdict(h, loc, pr.scales);
  });
  const auto settles = [&](const HypothesisFit& h) {
    return explains(pr, h, loc) && !leaves_play(h, loc) && !leaves_input_test(h, loc);
  };
  const bool stand_in_ahead =
      best != hs.end() && hs.front().score >= best->score + thresholds::kNestedMarginPct;
  if (settles(hs.front()) && (best == hs.end() || settles(*best)) && !stand_in_ahead)
    return done({});
  const std::vector<Candidate> paired = pair_candidates(pr, hs);
  std::vector<HypothesisFit> pairs = fit_all(pr, paired, base, o);
  std::vector<Candidate> tried = paired;
  for (auto& c : forward_pairs(pr, hs, paired, loc)) tried.push_back(std::move(c));
  for (auto& h : screen_and_refine(
           pr, {tried.begin() + static_cast<std::ptrdiff_t>(paired.size()), tried.end()}, base, o,
           kRefinedForwardPairs))
    pairs.push_back(std::move(h));
  const std::vector<Candidate> in_loop = loop_pairs(pr, hs, tried);
  for (auto& h : screen_and_refine(pr, in_loop, base, o, kRefinedLoopPairs))
    pairs.push_back(std::move(h));
  tried.insert(tried.end(), in_loop.begin(), in_loop.end());
  for (auto& h :
       screen_and_refine(pr, places_with_dominant(pr, hs, tried), base, o, kRefinedDominantPlaces))
    pairs.push_back(std::move(h));
  for (auto& h : gated_with_disturbances(pr, hs, base, o)) pairs.push_back(std::move(h));
  // Credible places first: their pairs may hold an effect that generalises a simpler one.
  for (auto& h : fit_all(pr, credible_pairs(hs, pairs), base, o)) pairs.push_back(std::move(h));
  std::vector<const HypothesisFit*> fitted_pairs;
  for (const auto& h : pairs) fitted_pairs.push_back(&h);
  for (auto& h : fit_all(pr, simpler_pairs(hs, fitted_pairs), base, o))
    pairs.push_back(std::move(h));
  return done(std::move(pairs));
}

}  // namespace rig::diagnose
