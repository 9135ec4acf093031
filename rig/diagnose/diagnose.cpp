#include "rig/diagnose/diagnose.hpp"

#include <chrono>
#include <cmath>
#include <optional>

#include "rig/diagnose/bus_frequency.hpp"
#include "rig/diagnose/evidence.hpp"
#include "rig/diagnose/screen.hpp"
#include "rig/diagnose/search.hpp"
#include "rig/diagnose/split.hpp"
#include "rig/diagnose/timing.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {
namespace {

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
    pr.level_step_removed_at = pr.level_shift_at;
    pr.level_shift_at = -1;
    pr.output_clip = {};  // its level no longer holds on both sides of the step
    base = model_output(pr, {});
  }
  r.baseline_yhat = base.yhat;
  const Eigen::ArrayXd used = pr.est_weight + pr.val_weight;
  r.fit_before_pct = weighted_fit_pct(pr.y, base.yhat, used);
  r.validation_fit_before_pct = weighted_fit_pct(pr.y, base.yhat, pr.val_weight);
  r.location = locate(pr, base.yhat);
  // The coupling test on the baseline alone (the other locations seed fits; it costs a
  // generalised least-squares fit per RC of its grid).
  r.location.coupling = locate_coupling(pr, pr.y - base.yhat, base.yhat);
  if (r.location.coupling_counts()) r.location.input_mismatch = true;
  if (step) {
    // The level before the step (y_level is the recorded mean over the whole record).
    const double after = 1.0 - *r.level_shift_time_s / pr.scales.duration_s;
    const double level = pr.y_level - *step * after;
    if (std::abs(level) > 0.0) {
      r.location.step_gain = locate_step_gain(pr, pr.y - base.yhat, base.yhat, 1.0 + *step / level);
      if (r.location.step_gain.fires) r.location.input_mismatch = true;
    }
  }
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
  DiagnoseInput input = in;
  if (in.bus_freq_hz) r.bus_frequency = take_out_bus_frequency(input, *in.bus_freq_hz);
  r.problem = prepare_problem(input, &r.blocks, &r.warmup);
  Problem& pr = r.problem;
  // The sampling convention (timing.hpp): when the baseline shifted by at most half a sample
  // explains the recording (without an operating-point step: that is a change of its own),
  // that is the answer (none); otherwise the effects are fitted against the model as given,
  // so that the shift takes nothing of theirs.
  Problem shifted = pr;
  if (const double delta = absorb_timing_nuisance(shifted); delta != 0.0) {
    DiagnoseResult s;
    locate_baseline(shifted, s);
    if (!s.location.input_mismatch && !s.location.disturbance && !s.level_shift_time_s) {
      pr = std::move(shifted);
      r.timing_nuisance_s = delta;
    }
  }
  const ModelOutput base = locate_baseline(pr, r);
  gate_to_windows(pr, r.location);
  r.hypotheses = r.location.worth_searching() ? search_hypotheses(pr, r.location, base.yhat, o)
                                              : blind_search(pr, r.location, base.yhat, o);
  drop_repeats(r.hypotheses);
  test_direction_on_spans(r);
  weigh_plays_on_two_level_input(r);
  r.chosen_index = choose(r, o.min_gain_pct, &r.drift_set_aside_index);
  if (map_of_the_move(r))
    r.chosen_index = r.drift_set_aside_index = -1;
  else if (r.chosen_index < 0 && !operating_point_moved(r))
    r.explained_below_min_gain = (r.chosen_index = explains_below_min_gain(r)) >= 0;
  // A verdict's parameters come from a full search, also when the procedure chose one the
  // screen ranked below the refined few.
  if (r.chosen_index >= 0 && r.chosen()->screened_only) {
    HypothesisFit& h = r.hypotheses[static_cast<std::size_t>(r.chosen_index)];
    const int screened = h.evaluations;
    h = fit_hypothesis(spanned(pr, h), {h.effects}, base.yhat, o.fit);
    h.evaluations += screened;
  }
  if (r.chosen_index >= 0) keep_pair_estimate(r, base.yhat, o);
  // The rule's own conditions, again on the hypothesis as refitted.
  if (r.explained_below_min_gain &&
      !(score_below_min_gain(r, *r.chosen()) > thresholds::kExplainedBelowMinGainPct &&
        explains(pr, *r.chosen(), r.location)))
    r.chosen_index = -1, r.explained_below_min_gain = false;
  // Nothing the input tests found, and nothing worth its parameters (a disturbance alone, a
  // clip, the blind search's best): not material.
  if (!r.location.input_mismatch && !r.chosen()) {
    r.verdict = "none";
  } else if (r.chosen()) {
    r.verdict = verdict_of(*r.chosen());
  } else {
    r.operating_point_move = operating_point_moved(r);
    r.verdict = r.operating_point_move ? "none" : "unexplained";
  }
  r.alternative_index = close_alternative(r);
  r.explanation = explain(r);
  r.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace rig::diagnose
