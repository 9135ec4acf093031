// The explanation a commissioning engineer reads: where the mismatch is, what the chosen
// effect means physically, and what adding it does to the validation fit, with numbers.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <string>

#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/drift_materiality.hpp"
#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/effects/common.hpp"
#include "rig/diagnose/gain_peak.hpp"
#include "rig/diagnose/governor_loop.hpp"
#include "rig/diagnose/thresholds.hpp"
#include "rig/diagnose/verdict.hpp"

namespace rig::diagnose {
namespace {

std::string where_in_frequency(const Location& loc) {
  const FrequencyBin* best = nullptr;
  for (const auto& b : loc.freq.bins)
    if (b.significant && (!best || b.residual_coherence > best->residual_coherence)) best = &b;
  if (!best || !loc.freq.band_hz) return "";
  const std::complex<double> e = best->measured / best->model;
  const double ph = std::arg(e) * 180.0 / std::numbers::pi;
  const auto [lo, hi] = *loc.freq.band_hz;
  const std::string where = fmt::format("{:.3g}", lo) == fmt::format("{:.3g}", hi)
                                ? fmt::format("near {:.3g} Hz", lo)  // one bin
                                : fmt::format("between {:.3g} and {:.3g} Hz", lo, hi);
  return fmt::format(
      "The measured response departs from the model {}: at {:.3g} Hz its gain is {:.0f} % of "
      "the model's and its phase is {:.0f} degrees {} it. ",
      where, best->freq_hz, 100.0 * std::abs(e), std::abs(ph), ph < 0 ? "behind" : "ahead of");
}

std::string where_in_time_and_level(const DiagnoseResult& r) {
  std::string s;
  const auto& pr = r.problem;
  const HypothesisFit* h = r.chosen();
  const Eigen::Index from = h ? h->active_from : pr.active_from;
  const Eigen::Index to = h && h->active_to >= 0 ? h->active_to : pr.active_to;
  if (from > 0 || to < pr.u.size())
    s += fmt::format("The mismatch is present only from {:.0f} s to {:.0f} s of the record. ",
                     static_cast<double>(from) * pr.dt_s, static_cast<double>(to) * pr.dt_s);
  const auto& a = r.location.amp;
  if (a.two_level_input) {
    s += "The input takes two levels (a PRBS): on it any static map of the bias is a gain and "
         "an offset, and a play or a slew limit acts alike on every step, so nonlinearities "
         "are looked for only inside the loop and at the output, and the input's direction is "
         "no evidence of a play";
    s += h && h->fit_shows_direction
             ? fmt::format(
                   "; a play or hysteresis loop there is shown by its fit alone, "
                   "{:.1f} points or more over every explanation without one. ",
                   thresholds::kTwoLevelPlayMarginPct)
             : ". ";
    return s;
  }
  if (a.amplitude_dependent && a.by_level.size() >= 2)
    s += fmt::format(
        "The gain the recording shows relative to the model is {:.2f} for the smallest "
        "and {:.2f} for the largest fifth of input levels, so the cause is nonlinear. ",
        a.by_level.front().gain, a.by_level.back().gain);
  if (a.sign_dependent)
    s += fmt::format("It differs between positive ({:.2f}) and negative ({:.2f}) excursions. ",
                     a.positive.gain, a.negative.gain);
  if (a.direction_dependent)
    s += fmt::format(
        "Each reversal of the input's direction shifts the output as {:.3g} input units "
        "would (play or friction). ",
        -a.rising.gain);
  else if (a.direction_beyond_lag_dependent)
    s += fmt::format(
        "Beside what a lag or a delay would add (the model's response to the input's rate), "
        "each reversal of the input's direction shifts the output (z {:.1f}): {}. ",
        a.direction_beyond_lag_z,
        a.direction_beyond_lag_z < 0.0
            ? "a play or friction inside the loop, which acts first as a lag"
            : "the sign opposite to a play's, as a slew limit inside the loop gives");
  return s;
}

double derived(const HypothesisFit& h, const std::string& key) {
  return effects::derived_or_nan(h, key);
}

// The effect's own sentence (rig/diagnose/effects/<word>.cpp).
std::string what_effect_means(const AppliedEffect& e, const HypothesisFit& h, const Problem& pr) {
  std::string s = effect_model(e.effect).explain(e, h, pr);
  if (e.place == Place::kInLoop)
    s += fmt::format(
        ", not on the bias itself but inside the governor's loop, after a lag of {:.0f} ms "
        "(the actuator or the rack; the values are the bias-% equivalents there)",
        1e3 * e.place_params.at(0));
  if (e.place == Place::kFeedback)
    s += fmt::format(
        ", not on the bias but in a feedback from the output: a restoring force of {:.2f} times "
        "the output's (bias-% equivalent) departure from that nonlinearity (a hysteretic "
        "spring)",
        e.place_params.at(0));
  // (A linear effect in the loop acts the same anywhere in it: its own sentence says so.)
  if (e.place == Place::kError && kind_of(e.effect) != EffectKind::kLinear)
    s += ", not on the bias but on the error of the loop the model closes (the bias less the "
         "output over the static gain, in bias-%: a governor's power error)";
  if (e.place == Place::kGovernorError)
    s += ", not on the bias but on the governor's error in the loop the model closes (the bias "
         "less what the governor sees of the output, in bias-%)";
  if (after_pi(e.place))
    s += fmt::format(
        ", not on the bias but after the governor's PI (integral time {:.2g} s, output lag "
        "{:.0f} ms), inside the loop that works against it (the actuator or the rack; the "
        "values are the bias-% equivalents there)",
        e.place_params.at(0), 1e3 * e.place_params.at(1));
  const auto shared = shared_feedback(h.effects);
  if (shared && e.place == Place::kGovernorLoop) {
    s += "; the governor sees the output through the same feedback";
  } else if (feedback_fitted(e.place)) {
    const LoopFeedback fb = loop_feedback(e.place_params);
    s += fmt::format(
        "; the governor sees, fitted, {:.2f} of the output and its rate times {:.0f} ms, "
        "filtered over {:.0f} ms",
        fb.static_share, 1e3 * fb.derivative_s, 1e3 * fb.filter_s);
  }
  if (e.place == Place::kOutput)
    s += fmt::format(
        ", not on the bias but on the measured output (the values are bias-% equivalents; "
        "times the static gain {:.4g} they are output units)",
        pr.scales.dc_gain);
  return s;
}

// What the response says about the step (locate.hpp StepGain).
std::string step_gain_words(const StepGain& g) {
  if (!g.tested) return "";
  const std::string measured =
      fmt::format("The input-driven response after the step is x{:.3f} +- {:.3f} of that before it",
                  1.0 + g.change, g.sd);
  if (g.decisive)
    return measured + fmt::format(
                          " (z = {:.1f}), as the level's x{:.3f} says: a measurement gain with the "
                          "level in it changed, not the operating point. ",
                          g.z, g.level_ratio);
  if (g.fires)
    return measured + fmt::format(
                          " (z = {:.1f}), as the level's x{:.3f} would ({:.0f} times as likely as "
                          "no change): a gain with the level in it changed, rather than the "
                          "operating point alone. ",
                          g.z, g.level_ratio, std::exp(g.log_likelihood_ratio));
  const bool agrees =
      std::abs(g.change - (g.level_ratio - 1.0)) <= thresholds::kStepGainAgreeSds * g.sd;
  if (std::abs(g.z) > thresholds::kStepGainZ)
    return measured + fmt::format(
                          ", not the level's x{:.3f}: the operating point changed, and "
                          "the gain with it. ",
                          g.level_ratio);
  if (!agrees)
    return measured + fmt::format(
                          ", which rules out a gain change of x{:.3f} with the level in "
                          "it: the operating point changed. ",
                          g.level_ratio);
  return measured + fmt::format(
                        ", consistent with a gain change of x{:.3f} but not much likelier than "
                        "none ({:.1f} times; {:.0f} asked). ",
                        g.level_ratio, std::exp(g.log_likelihood_ratio),
                        thresholds::kStepGainLikelihoodRatio);
}

// An operating-point step found in the recording (find_level_shift).
std::string level_shift_words(const DiagnoseResult& r) {
  if (!r.level_shift_time_s) return "";
  // The level before the step (y_level is the mean over the whole record).
  const double after = 1.0 - *r.level_shift_time_s / r.problem.scales.duration_s;
  const double level = r.problem.y_level - r.level_shift * after;
  const std::string of_level =
      std::abs(level) > 0.0
          ? fmt::format(
                " ({:+.1f} % of the operating level before it, {:.4g}: a gain change of x{:.3f} "
                "with the level in it steps it by as much)",
                100.0 * r.level_shift / level, level, 1.0 + r.level_shift / level)
          : "";
  return fmt::format(
             "The recorded level steps by {:+.4g} at {:.1f} s{} (an operating-point change, or a "
             "gain that changed with the operating point in it); the step is taken out before "
             "the fits. ",
             r.level_shift, *r.level_shift_time_s, of_level) +
         step_gain_words(r.location.step_gain);
}

// A disturbance the location found that no hypothesis makes worth its parameters.
// A clipped output (Problem::output_clip) is a saturation at the output the rig compares
// every model through; said first, as the level step is.
std::string clip_words(const DiagnoseResult& r) {
  const OutputClip& c = r.problem.output_clip;
  if (c.side == 0) return "";
  return fmt::format(
      "The recorded output is clipped: {} samples sit at exactly {:.6g}, its {} value (a "
      "saturation at the output: the end of the sensor's range, or a level held by an "
      "overflow); every model's output is clipped there too. ",
      c.samples, c.level, c.side > 0 ? "highest" : "lowest");
}

// What the search behind a dominant disturbance (search.cpp) found, when it named nothing.
std::string unseen_input_words(const DiagnoseResult& r) {
  const auto best = std::find_if(r.hypotheses.begin(), r.hypotheses.end(),
                                 [](const HypothesisFit& g) { return has_input_side(g); });
  if (best == r.hypotheses.end()) return "";
  return fmt::format(
      " The best input-side effect fitted beside the disturbance ({}) adds {:.1f} points "
      "of validation score to it, less than the {:.1f} asked when the input tests found "
      "nothing.",
      verdict_of(*best), best->score - disturbance_part_score(r.hypotheses, *best),
      thresholds::kUnseenInputGainPct);
}

// The blind search's best (search.hpp blind_search) when nothing was named.
std::string blind_words(const DiagnoseResult& r) {
  if (r.hypotheses.empty() || r.location.disturbance || r.location.clip.side != 0) return "";
  const HypothesisFit& best = r.hypotheses.front();
  return fmt::format(
      " Every input-side effect was fitted all the same: the best ({}) adds {:.1f} points of "
      "validation score, less than the {:.1f} asked when the input tests found nothing.",
      verdict_of(best), best.score, thresholds::kUnseenInputGainPct);
}

std::string negligible_disturbance(const DiagnoseResult& r) {
  if (!r.location.disturbance) return blind_words(r);
  const auto it = std::find_if(r.hypotheses.begin(), r.hypotheses.end(),
                               [](const HypothesisFit& g) { return !has_input_side(g); });
  if (it == r.hypotheses.end()) return "";
  const HypothesisFit& h = *it;
  if (h.name() == "drift")
    return fmt::format(
               " A slow drift of rms {:.3g} ({:.0f} % of the input-driven response, {:.2f} % of "
               "the "
               "output's mean level) was detected in the residual: the operating noise of a "
               "running "
               "set, not a missing effect (modelling it: validation fit {:.1f} % -> {:.1f} %).",
               derived(h, "drift_rms"), 100.0 * derived(h, "drift_rms") / r.problem.scales.z_std,
               r.problem.y_level != 0.0
                   ? 100.0 * derived(h, "drift_rms") / std::abs(r.problem.y_level)
                   : 0.0,
               h.validation_fit_before, h.validation_fit_after) +
           unseen_input_words(r);
  return fmt::format(
             " A periodic component was detected in the residual, but modelling it changes the "
             "validation fit only from {:.1f} % to {:.1f} %: not material.",
             h.validation_fit_before, h.validation_fit_after) +
         unseen_input_words(r);
}

double db_of_ln(double ln) { return 20.0 * ln / std::log(10.0); }

// What the choice and the alternative g make of a gain peak that tells them apart.
std::string peak_taken_words(const DiagnoseResult& r, const HypothesisFit& g,
                             const GainPeak& peak) {
  if (accounts_for(r, *r.chosen(), peak))
    return fmt::format("which the {} accounts for", r.verdict);
  const auto taken_db = [&](const HypothesisFit& h) {
    return std::max(0.0, db_of_ln(share_taken(r, h, peak) * peak.log_ratio));
  };
  return fmt::format(
      "of which the {} takes {:.1f} dB and it {:.1f} dB: the data's gain is "
      "nearer the {}'s shape",
      r.verdict, taken_db(*r.chosen()), taken_db(g), r.verdict);
}

// Another explanation that fits about as well (verdict.hpp close_alternative), if any.
std::string alternative_words(const DiagnoseResult& r) {
  if (r.alternative_index < 0) return "";
  const HypothesisFit& g = r.hypotheses[static_cast<std::size_t>(r.alternative_index)];
  // An alternative fitted beside the drift the verdict set aside is compared with the
  // chosen effect's own pair with it, like with like.
  const HypothesisFit* pair = set_aside_drift_pair(r);
  const bool with_drift = pair && has_drift(g);
  const double against = with_drift ? pair->score : r.chosen()->score;
  std::string names;
  for (const auto& e : g.effects) {
    if (kind_of(e.effect) == EffectKind::kDisturbance) continue;
    if (!names.empty()) names += " with ";
    names += std::string(to_string(e.effect)) + place_suffix(e.place);
  }
  const std::string a =
      !names.empty() && std::string("aeiou").find(names.front()) != std::string::npos ? "An" : "A";
  std::string s = fmt::format(
      " {} {} fits {} (validation score {:.2f} against {:.2f}{}): this recording does not tell "
      "the two apart.",
      a, names, g.score > against ? "as well or better" : "about as well", g.score, against,
      with_drift ? ", each with the drift beside it" : "");
  if (const auto peak = gain_peak_tells_apart(r, *r.chosen(), g))
    s = fmt::format(
        " {} {} scores {:.2f} against {:.2f}{} but leaves the gain the data show at {:.2f} Hz "
        "({:+.1f} dB against the model{}, beyond its uncertainty), {}.",
        a, names, g.score, against, with_drift ? " (each with the drift beside it)" : "",
        peak->freq_hz, db_of_ln(peak->signed_log),
        peak->from <= 0 ? std::string()
        : peak->to < 0  ? fmt::format(" from {:.0f} s", peak->from * r.problem.dt_s)
                        : fmt::format(" from {:.0f} s to {:.0f} s", peak->from * r.problem.dt_s,
                                      peak->to * r.problem.dt_s),
        peak_taken_words(r, g, *peak));
  if (r.location.amp.two_level_input)
    s += " On a two-level input every step is the same size, so a deadband, a play or a slew "
         "limit in the loop acts much as a gain or a lag would; a test whose bias varies in "
         "amplitude (Gaussian or shaped) can tell them apart.";
  return s;
}

// What became of a recorded bus frequency (bus_frequency.hpp), first: every fit below is
// of the output without the grid's share.
std::string bus_frequency_words(const DiagnoseResult& r) {
  if (!r.bus_frequency) return "";
  const std::string& n = r.bus_frequency->note;
  return n.empty() ? ""
                   : static_cast<char>(std::toupper(static_cast<unsigned char>(n[0]))) +
                         n.substr(1) + ". ";
}

// A `none` behind a grid event that moved the operating point (operating_point.cpp).
std::string operating_point_words(const DiagnoseResult& r) {
  const OperatingPointMove& m = *r.operating_point_move;
  const auto& t = r.location.tests;
  std::string s = fmt::format(
      "The grid's event at {:.1f} s moved the set's operating point by {:.3g} output units. ",
      m.event_s, m.step);
  if (!m.correlated)
    s += "The residual is not correlated with the input";
  else if (m.one_side_dependent)
    s += fmt::format(
        "The model explains the recording on one side of it; {} it the residual is correlated "
        "with the input (peak {:.2f} times the 99 % bound, threshold {:.2f} for either side)",
        m.dependent_after ? "after" : "before", m.cross_ratio, m.cross_threshold);
  else
    s += fmt::format(
        "The residual is correlated with the input over the whole record (peak {:.2f} times the "
        "99 % bound, threshold {:.2f}) but on neither side of the event alone (at most {:.2f}, "
        "threshold {:.2f}): each side is a linear answer of its own",
        t.cross_ratio, t.cross_threshold, m.cross_ratio, m.cross_threshold);
  if (m.band && r.location.freq.band_hz) {
    const auto [lo, hi] = *r.location.freq.band_hz;
    s += fmt::format(
        "; its answer departs from the model between {:.3g} and {:.3g} Hz over the "
        "whole record but {}",
        lo, hi,
        m.band_sides[0]   ? "before the event only"
        : m.band_sides[1] ? "after the event only"
                          : "on neither side of it alone");
  }
  if (r.location.amp.sign_dependent)
    s += fmt::format(
        "; the answers to a rise and to a fall differ over the whole record (z {:.1f}) but on "
        "neither side alone (z {:.1f} before, {:.1f} after); no other test fails",
        r.location.amp.sign_z, m.sign_z[0], m.sign_z[1]);
  else
    s += "; no other test fails";
  if (!r.hypotheses.empty())
    s += fmt::format(" (the best effect, {}, changes the validation fit from {:.1f} % to {:.1f} %)",
                     r.hypotheses.front().name(), r.hypotheses.front().validation_fit_before,
                     r.hypotheses.front().validation_fit_after);
  return s +
         ": a set's small-signal answer follows its operating point (a curved fuel map inside the "
         "speed loop), so the change is the operating point's, not a missing effect.";
}

}  // namespace

std::string explain(const DiagnoseResult& r) {
  const auto& t = r.location.tests;
  if (r.verdict == "none" && r.operating_point_move)
    return bus_frequency_words(r) + level_shift_words(r) + operating_point_words(r);
  if (r.verdict == "none")
    return bus_frequency_words(r) + level_shift_words(r) + clip_words(r) +
           fmt::format(
               "The model explains the recording within noise: fit {:.1f} % (validation {:.1f} %); "
               "the "
               "residual is independent of the input (largest cross-correlation {:.2f} of the 99 % "
               "bound, "
               "threshold {:.2f}), no frequency band disagrees beyond the H1 uncertainty and the "
               "gain "
               "does "
               "not depend on amplitude.",
               r.fit_before_pct, r.validation_fit_before_pct, t.cross_ratio, t.cross_threshold) +
           negligible_disturbance(r);
  std::string s = bus_frequency_words(r) + level_shift_words(r) + clip_words(r) +
                  where_in_frequency(r.location) + where_in_time_and_level(r);
  if (!t.independent)
    s += fmt::format(
        "The residual is correlated with the input (peak {:.1f} times the 99 % bound at a lag "
        "of {:.2f} s): dynamics are missing. ",
        t.cross_ratio, t.cross_peak_lag_s);
  else if (const int i = r.location.half_dependent; i >= 0) {
    const auto& half = r.location.halves[static_cast<std::size_t>(i)];
    s += fmt::format(
        "The residual is correlated with the input in the {} half of the record (peak {:.1f} "
        "times the 99 % bound, threshold {:.2f} for either half) but not over the whole: "
        "dynamics that changed during the record. ",
        i == 0 ? "first" : "second", half.cross_ratio, half.cross_threshold);
  }
  if (const CouplingTest& c = r.location.coupling; r.location.coupling_counts())
    s += fmt::format(
        "The residual follows the model's output through a low-pass of RC {:.1f} s with the "
        "coefficient {:.2f} +- {:.2f}, as an AC coupling of the output leaves it (-1; {:.1e} "
        "times as likely as none). ",
        c.rc_s, c.beta, c.sd, std::exp(c.log_likelihood_ratio));

  const HypothesisFit* h = r.chosen();
  if (!h) {
    s += "No effect of the library explains it: the best";
    if (!r.hypotheses.empty())
      s += fmt::format(" ({}) changes the validation fit from {:.1f} % to {:.1f} %.",
                       r.hypotheses.front().name(), r.hypotheses.front().validation_fit_before,
                       r.hypotheses.front().validation_fit_after);
    else
      s += " was not found.";
    return s;
  }
  if (!r.location.input_mismatch && r.location.clip.side == 0 && has_input_side(*h))
    s += fmt::format(
        "The input tests found no mismatch {}, but the effect diagnosed below, {}, adds {:.1f} "
        "points of validation score, more than the {:.1f} asked of an effect found this way. ",
        r.location.disturbance ? "beside the disturbance (its wander widens their bounds)"
                               : "(the residual over the excited band, or over the whole "
                                 "record, does not show it)",
        r.location.disturbance ? "fitted with it" : "fitted all the same",
        h->score - disturbance_part_score(r.hypotheses, *h), thresholds::kUnseenInputGainPct);
  std::string what;
  for (const auto& e : h->effects) {
    if (!what.empty()) what += "; together with that, ";
    what += what_effect_means(e, *h, r.problem);
  }
  s += fmt::format(
      "Diagnosis: {}. Adding it raises the validation fit from {:.1f} % to {:.1f} % "
      "(estimation {:.1f} % to {:.1f} %).",
      what, h->validation_fit_before, h->validation_fit_after, h->fit_before, h->fit_after);
  if (const HypothesisFit* pair = set_aside_drift_pair(r))
    s += fmt::format(
        " Fitted with a drift beside it, it scores {:.2f} (validation score; {:.2f} alone); the "
        "drift alone is within the set's own slow wander, not material, so it is set aside.",
        pair->score, h->score);
  if (!r.location.input_mismatch && r.location.clip.side == 0 && !has_input_side(*h))
    s += unseen_input_words(r);
  if (r.explained_below_min_gain && score_below_min_gain(r, *h) != h->score)
    s += fmt::format(
        " It scores {:.2f}, under the {:.1f} asked, but the level's step fixed its value: the "
        "gain costs the fit no parameter, and the fit rises. Its residual is no longer "
        "correlated with the input.",
        h->score, thresholds::kMinGainPct);
  else if (r.explained_below_min_gain)
    s += fmt::format(
        " It scores {:.2f}, under the {:.1f} asked, but its residual is no longer correlated "
        "with the input: the rest of the residual, which the fit's points are measured "
        "against, is not the input's.",
        h->score, thresholds::kMinGainPct);
  return s + alternative_words(r);
}

}  // namespace rig::diagnose
