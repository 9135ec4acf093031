#include "rig/diagnose/evidence.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <utility>
#include <vector>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/locate.hpp"
#include "rig/diagnose/thresholds.hpp"

namespace rig::diagnose {

using thresholds::kDirectionBeyondLagZ;
using thresholds::kDirectionEvidenceZ;

bool has_direction_effect(const HypothesisFit& h) {
  return std::any_of(h.effects.begin(), h.effects.end(), [](const AppliedEffect& e) {
    return effect_model(e.effect).needs_direction_evidence;
  });
}

namespace {

bool nonlinear(const AppliedEffect& e) {
  const EffectKind k = kind_of(e.effect);
  return k == EffectKind::kInputNonlinearity || k == EffectKind::kFeedback;
}

}  // namespace

bool static_maps_only(const HypothesisFit& h) {
  return std::all_of(h.effects.begin(), h.effects.end(), [](const AppliedEffect& e) {
    return !nonlinear(e) || effect_model(e.effect).level_shaped;
  });
}

bool memoryless_static_maps_only(const HypothesisFit& h, const DataScales& scales) {
  return static_maps_only(h) &&
         std::all_of(h.effects.begin(), h.effects.end(), [&](const AppliedEffect& e) {
           const auto memory = effect_model(e.effect).has_memory;
           return !nonlinear(e) || (e.place_params.empty() && e.place != Place::kFeedback &&
                                    !(memory && memory(e, scales)));
         });
}

// Whether h acts on a span of its own (an onset found for it), not the problem's.
bool spanned_alone(const Problem& pr, const HypothesisFit& h) {
  const auto end = [&pr](Eigen::Index to) { return to < 0 ? pr.y.size() : to; };
  return h.active_from != pr.active_from || end(h.active_to) != end(pr.active_to);
}

// Every effect of h that needs the direction test's evidence has it (thresholds.hpp): on
// the input's direction of motion, or for a loop in an output feedback (a hysteretic spring
// follows the output's motion) on the output's.
bool direction_evidenced(const HypothesisFit& h, const Location& loc) {
  return std::none_of(h.effects.begin(), h.effects.end(), [&](const AppliedEffect& e) {
    // On a two-level input the input's direction is linear in du/dt: no evidence. On the
    // record, or on the hypothesis's own span.
    const double input_z =
        loc.amp.two_level_input
            ? (h.fit_shows_direction ? kDirectionEvidenceZ : 0.0)
            : std::max(std::abs(loc.amp.direction_z), std::abs(h.span_direction_z));
    const double z = e.place == Place::kFeedback ? loc.amp.output_direction_z : input_z;
    return effect_model(e.effect).needs_direction_evidence && std::abs(z) < kDirectionEvidenceZ;
  });
}

// A play's direction effect beyond what any lag or delay adds (thresholds.hpp): the sign of
// a play's (it subtracts b sign(du/dt) from the input it acts on).
// On the whole record, or for a hypothesis gated to a span (an effect from an onset) on that
// span alone: there the whole record's test dilutes it (droopsim seed 2 d037, a play from
// 102 s: z -2.29 on the record).
bool play_beyond_lag(const DiagnoseResult& r, const HypothesisFit& h) {
  const Location& loc = r.location;
  if (loc.amp.two_level_input) return false;
  if (loc.amp.direction_beyond_lag_z <= -kDirectionBeyondLagZ) return true;
  if (!spanned_alone(r.problem, h)) return false;
  const Eigen::VectorXd residual = r.problem.y - r.baseline_yhat;
  return direction_beyond_lag_z(r.problem, residual, r.baseline_yhat, h.active_from, h.active_to) <=
         -kDirectionBeyondLagZ;
}

// Every nonlinearity of h is a static map of the level (EffectModel::level_shaped) and the
// location's level test saw the gain depend on the input's amplitude (thresholds.hpp
// kLevelEvidenceChi2, and the gains' spread): what no gain, lag or delay does, so such a map
// needs no margin over them (droopsim seed 4 d034, a speed-error deadband behind the grid's
// wander, level chi^2 40.7: the deadband scored 0.69 points over a gain change with a delay).
// For a hypothesis gated to a span (an effect from an onset) the test is repeated on that
// span alone, as the direction test is (play_beyond_lag): the whole record's dilutes it
// (droopsim seed 7 d032, a deadband from 100 s: chi^2 21.5 but the outer levels' gains 1.2 %
// apart over the record, 27.2 and 8.2 % on its span).
//
// The sign test is such evidence too (thresholds.hpp kSignEvidenceZ): a gain that differs
// between positive and negative excursions (droopsim seed 13 d027, a smoke limiter from
// 100 s behind the wander, sign z -7.2: the limiter with the drift scored 0.13 points over a
// gain change with it and was named `gain_change`).
bool level_evidenced(const DiagnoseResult& r, const HypothesisFit& h) {
  const AmplitudeLocation& amp = r.location.amp;
  if (amp.two_level_input || !static_maps_only(h)) return false;
  if (LevelTest{amp.by_level, amp.level_chi2}.exceeds(thresholds::kLevelEvidenceChi2)) return true;
  if (std::abs(amp.sign_z) > thresholds::kSignEvidenceZ) return true;
  if (!spanned_alone(r.problem, h)) return false;
  const Eigen::VectorXd residual = r.problem.y - r.baseline_yhat;
  return level_test(r.problem, residual, r.baseline_yhat, h.active_from, h.active_to)
      .exceeds(thresholds::kLevelEvidenceChi2);
}

void test_direction_on_spans(DiagnoseResult& r) {
  const Problem& pr = r.problem;
  if (r.location.amp.two_level_input) return;
  const Eigen::VectorXd residual = pr.y - r.baseline_yhat;
  std::vector<std::pair<std::pair<Eigen::Index, Eigen::Index>, double>> done;  // per span
  for (auto& h : r.hypotheses) {
    const bool input_play = std::any_of(h.effects.begin(), h.effects.end(), [](const auto& e) {
      return effect_model(e.effect).needs_direction_evidence && e.place != Place::kFeedback;
    });
    if (!input_play || !spanned_alone(pr, h)) continue;
    const std::pair<Eigen::Index, Eigen::Index> span{h.active_from, h.active_to};
    auto hit =
        std::find_if(done.begin(), done.end(), [&](const auto& d) { return d.first == span; });
    if (hit == done.end()) {
      done.emplace_back(span, direction_z(pr, residual, r.baseline_yhat, span.first, span.second));
      hit = std::prev(done.end());
    }
    h.span_direction_z = hit->second;
  }
}

namespace {
bool has_play(const HypothesisFit& h) {
  return std::any_of(h.effects.begin(), h.effects.end(), [](const AppliedEffect& e) {
    return effect_model(e.effect).needs_direction_evidence;
  });
}
}  // namespace

void weigh_plays_on_two_level_input(DiagnoseResult& r) {
  if (!r.location.amp.two_level_input) return;
  double best_other = -std::numeric_limits<double>::infinity();
  for (const auto& h : r.hypotheses)
    if (!has_play(h) && std::isfinite(h.score)) best_other = std::max(best_other, h.score);
  for (auto& h : r.hypotheses) {
    const bool inside = std::none_of(h.effects.begin(), h.effects.end(), [](const auto& e) {
      return effect_model(e.effect).needs_direction_evidence && e.place == Place::kInput;
    });
    h.fit_shows_direction = has_play(h) && inside && std::isfinite(h.score) &&
                            h.score >= best_other + thresholds::kTwoLevelPlayMarginPct;
  }
}

}  // namespace rig::diagnose
