// The pairs the hypothesis search fits (docs/diagnose.md, Method step 3): which two effects
// can share a model, and which pairs are formed from the ranked singles and from the pairs
// already fitted. Internal to search.cpp.
#pragma once

#include <vector>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/screen.hpp"

namespace rig::diagnose {

// Whether a and b can share a model: one effect per loop place, and the error loop (whose
// correction goes through the linear part only, error_loop.hpp) with no other loop.
bool pairable(const AppliedEffect& a, const AppliedEffect& b);

// Whether an effect is tried at more than one place.
bool several_places(Effect e);

// The pair a + b started from both singles' fits and from b's own starting points at its
// place, seeded from `left`, the location of what a leaves; b listed first with b_first.
Candidate pair_starts(const AppliedEffect& a, const AppliedEffect& b, const Problem& problem,
                      const Location& left, bool b_first = false);

// Pairs of the best input-side singles (the best place of each effect), and of those with a
// detected disturbance.
std::vector<Candidate> pair_candidates(const Problem& problem,
                                       const std::vector<HypothesisFit>& singles);

// Whether the pair a + b (either order, same places) is among the candidates cs.
bool fitted(const std::vector<Candidate>& cs, const AppliedEffect& a, const AppliedEffect& b);

// A forward step from the best input-side single that could be a verdict, and from the best
// linear one, with every other input-side effect at its best place (not among `existing`).
std::vector<Candidate> forward_pairs(const Problem& problem,
                                     const std::vector<HypothesisFit>& singles,
                                     const std::vector<Candidate>& existing,
                                     const Location& location);

// For the best few fitted pairs with an effect that generalises a simpler one, the pair with
// the simpler one at its best single place (verdict.cpp prefer_simpler compares them).
std::vector<Candidate> simpler_pairs(const std::vector<HypothesisFit>& singles,
                                     std::vector<const HypothesisFit*> pairs);

// For the best few fitted pairs with an effect whose place stopped at a bound, the pair with
// that effect at its best credible single place beside the same other effect (not among
// `pairs`).
std::vector<Candidate> credible_pairs(const std::vector<HypothesisFit>& singles,
                                      const std::vector<HypothesisFit>& pairs);

// When a disturbance dominates the residual: every other place of each input-side
// nonlinearity paired with that disturbance (not among `existing`).
std::vector<Candidate> places_with_dominant(const Problem& problem,
                                            const std::vector<HypothesisFit>& singles,
                                            const std::vector<Candidate>& existing);

// The best linear single inside the governor's loop beside each nonlinearity at its best place
// on the loop's error (not among `existing`).
std::vector<Candidate> loop_pairs(const Problem& problem, const std::vector<HypothesisFit>& singles,
                                  const std::vector<Candidate>& existing);

}  // namespace rig::diagnose
