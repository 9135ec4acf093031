#include "rig/diagnose/pairs.hpp"

#include <algorithm>
#include <optional>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/governor_loop.hpp"
#include "rig/diagnose/placement.hpp"
#include "rig/diagnose/split.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {
namespace {

using thresholds::kDominantDisturbanceGainPct;
using thresholds::kPairedInputSingles;
using thresholds::kPairedWithDisturbance;
using thresholds::kRefinedForwardPairs;

// Places that hold one effect only (one front lag, one feedback path, one error loop).
bool one_per_record(Place p) {
  return p == Place::kInLoop || p == Place::kFeedback || in_error_loop(p) ||
         p == Place::kGovernorLoop;
}

// Two forms of one thing: the two lags (told apart afterwards), or two forms of one word (a
// resonance as a factor and as the model's modes moved).
bool twins(Effect a, Effect b) {
  const auto lag = [](Effect e) { return e == Effect::kExtraLag || e == Effect::kSensorLag; };
  return (lag(a) && lag(b)) || std::string_view(to_string(a)) == to_string(b);
}

}  // namespace

// Whether a and b can share a model: one effect per loop place, and the error loop (whose
// correction goes through the linear part only, error_loop.hpp) with no other loop.
bool pairable(const AppliedEffect& a, const AppliedEffect& b) {
  if (a.place == b.place && one_per_record(a.place)) return false;
  const auto loop = [](const AppliedEffect& e) {
    return e.place == Place::kInLoop || e.place == Place::kFeedback ||
           kind_of(e.effect) == EffectKind::kFeedback;
  };
  const auto error_loop = [](const AppliedEffect& e) {  // (the governor loop's changes G)
    return in_error_loop(e.place) || e.place == Place::kGovernorLoop;
  };
  // ... but a linear effect inside the governor's loop beside an effect on its error that
  // fits the loop's feedback: both then close the loop with that feedback (governor_loop.hpp).
  if (error_loop(a) && error_loop(b)) return shared_feedback(std::vector{a, b}).has_value();
  return !((error_loop(a) && loop(b)) || (error_loop(b) && loop(a)));
}

namespace {

// Whether a and b close the governor's loop with one feedback (governor_loop.hpp).
bool share(const AppliedEffect& a, const AppliedEffect& b) {
  return shared_feedback(std::vector{a, b}).has_value();
}

// The best fitted place of effect e that can sit beside b (singles are ranked), with its own
// feedback when `apart`; nullptr when none can.
const AppliedEffect* best_place_beside(const std::vector<HypothesisFit>& singles, Effect e,
                                       const AppliedEffect& b, bool apart = false) {
  for (const auto& h : singles)
    if (h.effects.size() == 1 && h.effects[0].effect == e && pairable(h.effects[0], b) &&
        !(apart && share(h.effects[0], b)))
      return &h.effects[0];
  return nullptr;
}

}  // namespace

// Whether an effect is tried at more than one place (singles below).
bool several_places(Effect e) {
  const EffectModel& m = effect_model(e);
  return kind_of(e) == EffectKind::kInputNonlinearity ||
         (kind_of(e) == EffectKind::kLinear && (m.apply_on_error || m.loop_factor));
}

// The pair a + b started from both singles' fits and from b's own starting points at its
// place, seeded from `left`, the location of what a leaves (b's single may have taken a's part
// as well: a dead time the lag of a slew limit, a limit fitted without the drift beside it).
Candidate pair_starts(const AppliedEffect& a, const AppliedEffect& b, const Problem& pr,
                      const Location& left, bool b_first) {
  Candidate c;
  const auto add = [&](const AppliedEffect& x) {
    c.push_back(b_first ? std::vector<AppliedEffect>{x, a} : std::vector<AppliedEffect>{a, x});
  };
  add(b);
  for (auto& start : placed_starts(b.effect, b.place, pr, left)) add(start.front());
  // Two effects closing the governor's loop with one feedback start from each one's fitted
  // feedback: from the lag's, the pair is the lag's single with the nonlinearity added.
  if (const auto s = shared_feedback(c.front())) {
    for (std::size_t i = 0, n = c.size(); i < n; ++i) {
      std::vector<AppliedEffect> v = c[i];
      std::vector<double>& to = v[s->error].place_params;
      const std::vector<double>& from = v[s->loop].place_params;
      std::copy(from.end() - 3, from.end(), to.end() - 3);
      c.push_back(std::move(v));
    }
  }
  return c;
}

// Pairs of the best input-side singles (the best place of each effect), and of those with a
// detected disturbance; every input-side effect with a disturbance that dominates the
// residual (its single's score, fitted without it, says little then).
std::vector<Candidate> pair_candidates(const Problem& pr,
                                       const std::vector<HypothesisFit>& singles) {
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
  std::vector<std::optional<Location>> left(dists.size());
  std::vector<Candidate> out;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const AppliedEffect& a = inputs[i]->effects[0];
    for (std::size_t j = i + 1; j < std::min(inputs.size(), kPairedInputSingles); ++j) {
      const AppliedEffect& b = inputs[j]->effects[0];
      if (i >= kPairedInputSingles || twins(a.effect, b.effect)) continue;
      if (!pairable(a, b)) continue;  // one front lag, one feedback path, one error loop
      out.push_back({{a, b}});
    }
    for (std::size_t j = 0; j < dists.size(); ++j) {
      if (i >= kPairedWithDisturbance && !(dominant && j == 0)) continue;
      if (!left[j]) left[j] = locate(pr, dists[j]->yhat);  // a was fitted without it
      out.push_back(pair_starts(dists[j]->effects[0], a, pr, *left[j], true));
    }
  }
  return out;
}

// Whether the pair a + b (either order, same places) is among the candidates cs.
bool fitted(const std::vector<Candidate>& cs, const AppliedEffect& a, const AppliedEffect& b) {
  const auto same = [](const AppliedEffect& x, const AppliedEffect& y) {
    return x.effect == y.effect && x.place == y.place;
  };
  return std::any_of(cs.begin(), cs.end(), [&](const Candidate& c) {
    const auto& p = c.front();
    return p.size() == 2 && ((same(p[0], a) && same(p[1], b)) || (same(p[0], b) && same(p[1], a)));
  });
}

// A forward step from the best input-side single that could be a verdict, from the best
// linear one (a nonlinearity in the loop can stand in for a lag, and the lag's pair with a
// gain is then never formed) and from the best with a nonlinearity (a lag in the loop can
// stand in for a hysteresis beside damper windings, droopsim s11 d079, and the hysteresis's
// pair with the damping is then never formed): each with every other input-side effect at
// its best place, but for the pairs already among `existing`.
std::vector<Candidate> forward_pairs(const Problem& pr, const std::vector<HypothesisFit>& singles,
                                     const std::vector<Candidate>& existing, const Location& loc) {
  std::vector<Candidate> out;
  enum class First { kAny, kLinear, kNonlinear };
  for (const First kind : {First::kAny, First::kLinear, First::kNonlinear}) {
    const auto first = std::find_if(singles.begin(), singles.end(), [&](const HypothesisFit& h) {
      return h.effects.size() == 1 && has_input_side(h) && could_be_verdict(h, loc, pr.scales) &&
             (kind == First::kAny || has_nonlinearity(h) == (kind == First::kNonlinear));
    });
    if (first == singles.end()) continue;
    const AppliedEffect& a = first->effects[0];
    const Location after_a = locate(pr, first->yhat);
    std::vector<Effect> seen{a.effect}, best_seen{a.effect};
    for (const auto& h : singles) {  // ranked: each effect's best place that can pair with a
      if (h.effects.size() != 1 || !has_input_side(h)) continue;
      const AppliedEffect& b = h.effects[0];
      if (twins(a.effect, b.effect)) continue;
      // b at its best place, beside a's best place that can sit with it (a lag in the
      // governor's loop and a play after its PI share the loop: the lag at the input then).
      if (std::find(best_seen.begin(), best_seen.end(), b.effect) == best_seen.end()) {
        best_seen.push_back(b.effect);
        // (and, where they would share the governor's feedback, apart as well)
        if (!pairable(a, b) || share(a, b))
          if (const AppliedEffect* a2 = best_place_beside(singles, a.effect, b, true))
            if (!fitted(existing, *a2, b) && !fitted(out, *a2, b))
              out.push_back(pair_starts(*a2, b, pr, after_a));
      }
      if (std::find(seen.begin(), seen.end(), b.effect) != seen.end()) continue;
      if (!pairable(a, b)) continue;  // its next place may pair (a dead time in the error loop)
      // A pair sharing the governor's feedback is a different model from b at its next place
      // beside a (F-16 Level 7: the map after the PI, a dead time at the input): form both.
      if (!share(a, b)) seen.push_back(b.effect);
      if (fitted(existing, a, b) || fitted(out, a, b)) continue;
      out.push_back(pair_starts(a, b, pr, after_a));
    }
  }
  return out;
}

// The best few pairs with an effect that generalises a simpler one (a resonance a damping
// change, a hysteresis loop a play) beside the same other effect, the simpler one at its best
// single place: verdict.cpp (prefer_simpler) names the general one only when it beats that
// pair, which must then have been fitted (droopsim's damper windings: a resonance with a lead
// of 12-18 ms beside it, the damping change's pair with the lead never formed, or formed from
// the lead's own single, which found none). It starts from the general pair's other effect as
// fitted there.
std::vector<Candidate> simpler_pairs(const std::vector<HypothesisFit>& singles,
                                     std::vector<const HypothesisFit*> pairs) {
  std::sort(pairs.begin(), pairs.end(),
            [](const HypothesisFit* a, const HypothesisFit* b) { return a->score > b->score; });
  if (pairs.size() > kRefinedForwardPairs) pairs.resize(kRefinedForwardPairs);
  std::vector<Candidate> out;
  for (const HypothesisFit* h : pairs) {
    if (h->effects.size() != 2) continue;
    for (std::size_t k = 0; k < 2; ++k) {
      const auto simpler = effect_model(h->effects[k].effect).generalises;
      if (!simpler || h->effects[1 - k].effect == *simpler) continue;
      const AppliedEffect& other = h->effects[1 - k];
      const auto best = std::find_if(singles.begin(), singles.end(), [&](const HypothesisFit& g) {
        return g.effects.size() == 1 && g.effects[0].effect == *simpler &&
               pairable(g.effects[0], other);  // its best place that can sit beside the other
      });
      if (best == singles.end()) continue;
      std::vector<AppliedEffect> pair = h->effects;
      pair[k] = best->effects[0];
      if (fitted(out, pair[0], pair[1])) continue;  // fitted before, it started elsewhere
      out.push_back({pair});
    }
  }
  return out;
}

// The best few pairs with an effect whose place stopped at a bound (place_credible, which the
// verdict skips) refitted with that effect at its best credible single place, started from the
// other effect as the pair fitted it. The forward pairs take each effect at its best single
// place: a lag inside the governor's loop whose feedback stops at its bound beside a damping
// or gain change was fitted, the lag's credible place at the input beside it never (gensim
// g073, g075: a transducer's lag or gain beside the combustion's lag or damper windings).
std::vector<Candidate> credible_pairs(const std::vector<HypothesisFit>& singles,
                                      const std::vector<HypothesisFit>& pairs) {
  // A pair fitted with the lag's other word at the same place is the same model (the
  // sensor lag's twin, search.cpp): fitted again it would only tie with it.
  const auto fitted_or_twin = [](const std::vector<Candidate>& cs, const AppliedEffect& a,
                                 const AppliedEffect& b) {
    const auto twin = [](AppliedEffect e) {
      if (e.effect == Effect::kExtraLag || e.effect == Effect::kSensorLag)
        e.effect = e.effect == Effect::kExtraLag ? Effect::kSensorLag : Effect::kExtraLag;
      return e;
    };
    return fitted(cs, a, b) || fitted(cs, twin(a), b) || fitted(cs, a, twin(b));
  };
  std::vector<const HypothesisFit*> stopped;
  std::vector<Candidate> fitted_pairs;
  for (const auto& h : pairs) {
    if (h.effects.size() != 2) continue;
    fitted_pairs.push_back({h.effects});
    if (!std::all_of(h.effects.begin(), h.effects.end(), place_credible)) stopped.push_back(&h);
  }
  std::sort(stopped.begin(), stopped.end(),
            [](const HypothesisFit* a, const HypothesisFit* b) { return a->score > b->score; });
  if (stopped.size() > kRefinedForwardPairs) stopped.resize(kRefinedForwardPairs);
  std::vector<Candidate> out;
  for (const HypothesisFit* h : stopped) {
    for (std::size_t k = 0; k < 2; ++k) {
      const AppliedEffect& at_bound = h->effects[k];
      const AppliedEffect& other = h->effects[1 - k];
      if (place_credible(at_bound) || !place_credible(other)) continue;
      const auto best = std::find_if(singles.begin(), singles.end(), [&](const HypothesisFit& g) {
        const AppliedEffect& e = g.effects[0];
        return g.effects.size() == 1 && e.effect == at_bound.effect && e.place != at_bound.place &&
               place_credible(e) && pairable(e, other);
      });
      if (best == singles.end() || fitted_or_twin(fitted_pairs, best->effects[0], other) ||
          fitted_or_twin(out, best->effects[0], other))
        continue;
      // The better single first (it names the verdict): the moved effect's single at its
      // credible place against the other's single at its place.
      const auto other_single = std::find_if(singles.begin(), singles.end(), [&](const auto& g) {
        return g.effects.size() == 1 && g.effects[0].effect == other.effect &&
               g.effects[0].place == other.place;
      });
      const bool moved_first = other_single == singles.end() || best->score >= other_single->score;
      out.push_back({moved_first ? std::vector{best->effects[0], other}
                                 : std::vector{other, best->effects[0]}});
    }
  }
  return out;
}

// When a disturbance dominates the residual, each input-side nonlinearity was placed (its
// best place ranked) without it: every other place of it is paired with that disturbance
// too, screened as the forward pairs are (a governor's error deadband behind a drift).
std::vector<Candidate> places_with_dominant(const Problem& pr,
                                            const std::vector<HypothesisFit>& singles,
                                            const std::vector<Candidate>& existing) {
  const auto dist = std::find_if(singles.begin(), singles.end(),
                                 [](const HypothesisFit& h) { return !has_input_side(h); });
  if (dist == singles.end() || dist->score < kDominantDisturbanceGainPct) return {};
  const Location left = locate(pr, dist->yhat);
  std::vector<Candidate> out;
  for (const auto& h : singles) {
    if (h.effects.size() != 1 || !several_places(h.effects[0].effect)) continue;
    if (!fitted(existing, h.effects[0], dist->effects[0]))
      out.push_back(pair_starts(dist->effects[0], h.effects[0], pr, left, true));
  }
  return out;
}

// The governor's loop often holds two effects (a speed-error deadband and a slow combustion:
// droopsim d078): the best linear single inside the loop beside each nonlinearity at its best
// place on the loop's error that fits the feedback (governor_error, governor_pi), the two
// closing the loop with one feedback. Started from both singles' fits and from the linear
// effect's own seeds on what the nonlinearity leaves.
std::vector<Candidate> loop_pairs(const Problem& pr, const std::vector<HypothesisFit>& singles,
                                  const std::vector<Candidate>& existing) {
  const auto lag = std::find_if(singles.begin(), singles.end(), [](const HypothesisFit& h) {
    return h.effects.size() == 1 && h.effects[0].place == Place::kGovernorLoop;
  });
  std::vector<Candidate> out;
  if (lag == singles.end()) return out;
  const AppliedEffect& b = lag->effects[0];
  std::vector<Effect> seen;
  for (const auto& h : singles) {  // ranked: each nonlinearity's best place beside the lag
    if (h.effects.size() != 1) continue;
    const AppliedEffect& a = h.effects[0];
    if (kind_of(a.effect) != EffectKind::kInputNonlinearity || !pairable(a, b) ||
        std::find(seen.begin(), seen.end(), a.effect) != seen.end())
      continue;
    seen.push_back(a.effect);
    if (!fitted(existing, a, b)) out.push_back(pair_starts(a, b, pr, locate(pr, h.yhat)));
  }
  return out;
}

}  // namespace rig::diagnose
