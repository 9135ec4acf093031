// The explanation a commissioning engineer reads: where the mismatch is, what the chosen
// effect means physically, and what adding it does to the validation fit, with numbers.
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <string>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose {
namespace {

std::string where_in_frequency(const Location& loc) {
  const FrequencyBin* best = nullptr;
  for (const auto& b : loc.freq.bins)
    if (b.significant && (!best || b.residual_coherence > best->residual_coherence)) best = &b;
  if (!best || !loc.freq.band_hz) return "";
  const std::complex<double> e = best->measured / best->model;
  const double ph = std::arg(e) * 180.0 / std::numbers::pi;
  return fmt::format(
      "The measured response departs from the model between {:.3g} and {:.3g} Hz: at {:.3g} Hz "
      "its gain is {:.0f} % of the model's and its phase is {:.0f} degrees {} it. ",
      loc.freq.band_hz->first, loc.freq.band_hz->second, best->freq_hz, 100.0 * std::abs(e),
      std::abs(ph), ph < 0 ? "behind" : "ahead of");
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
  return s;
}

double derived(const HypothesisFit& h, const std::string& key) {
  for (const auto& [k, v] : h.derived)
    if (k == key) return v;
  return std::nan("");
}

// A limit inside an integrating loop loses position that the loop restores slowly.
std::string in_loop_words(const std::vector<double>& p, std::size_t i, double dt_s) {
  if (p.size() <= i || p[i] < 5.0 * dt_s) return "";
  return fmt::format(
      ", inside an integrating loop (a governor integrator with anti-windup) that restores the "
      "lost position with a time constant of {:.3g} s",
      p[i]);
}

std::string what_effect_means(const AppliedEffect& e, const HypothesisFit& h, const Problem& pr) {
  const auto& p = e.params;
  const double su = pr.scales.u_std;
  switch (e.effect) {
    case Effect::kDeadTime:
      return p[0] >= 0 ? fmt::format(
                             "a dead time of {:.0f} ms is missing (the recording's is {:.0f} ms, "
                             "the model's {:.0f} ms)",
                             1e3 * p[0], 1e3 * (pr.tf.delay_s + p[0]), 1e3 * pr.tf.delay_s)
                       : fmt::format("the model's dead time is {:.0f} ms too long", -1e3 * p[0]);
    case Effect::kExtraLag:
      return fmt::format(
          "a first-order lag of {:.0f} ms (corner {:.2f} Hz) is missing in the plant", 1e3 * p[0],
          1.0 / (2.0 * std::numbers::pi * p[0]));
    case Effect::kSensorLag: {
      const double ratio = derived(h, "noise_rolloff_ratio");
      if (!std::isfinite(ratio)) {
        // The corner is too near half the sample rate for two noise bands around it.
        return fmt::format(
            "the measurement lags by {:.0f} ms more than modelled (corner {:.1f} Hz, too near "
            "half the sample rate for the noise to tell the transducer from the plant)",
            1e3 * p[0], 1.0 / (2.0 * std::numbers::pi * p[0]));
      }
      return fmt::format(
          "the measurement lags by {:.0f} ms more than modelled; the noise is filtered "
          "too (noise above the corner is {:.2f} of that below), so it is the transducer",
          1e3 * p[0], ratio);
    }
    case Effect::kResonance:
      return fmt::format(
          "an unmodelled resonance at {:.2f} Hz (damping ratio {:.3f}, gain x{:.2f} at its peak)",
          p[0], p[1], p[2]);
    case Effect::kAcCoupling:
      return fmt::format(
          "the output passed through an AC coupling with RC = {:.2f} s (corner {:.3f} Hz) "
          "that the model lacks",
          p[0], 1.0 / (2.0 * std::numbers::pi * p[0]));
    case Effect::kDeadband:
      return fmt::format(
          "inputs within +-{:.3g} of the operating point ({:.0f} % of the input's standard "
          "deviation) have no effect: a deadband",
          p[0], 100.0 * p[0] / su);
    case Effect::kBacklash:
      return fmt::format(
          "a reversal of the input is lost for {:.3g} ({:.0f} % of the input's standard "
          "deviation): backlash of total width {:.3g}",
          2 * p[0], 200.0 * p[0] / su, 2 * p[0]);
    case Effect::kSaturation:
      return fmt::format(
          "the input is limited at +{:.3g} / -{:.3g} about the operating point "
          "({:.1f} / {:.1f} standard deviations){}",
          p[0], p[1], p[0] / su, p[1] / su, in_loop_words(p, 2, pr.dt_s));
    case Effect::kRateLimit:
      return fmt::format("the input cannot change faster than {:.3g} per second{}", p[0],
                         in_loop_words(p, 1, pr.dt_s));
    case Effect::kStaticNonlinearity:
      return fmt::format(
          "the static gain changes with level: at +1 standard deviation it is {:.2f}, at -1 "
          "it is {:.2f} times the small-signal gain",
          1 + p[0] + p[1], 1 - p[0] + p[1]);
    case Effect::kNonlinearStiffness:
      return fmt::format(
          "the stiffness changes with amplitude: {:+.0f} % at one standard deviation of the output",
          100.0 * p[0]);
    case Effect::kCoulombFriction:
      return fmt::format(
          "a friction force of {:.3g} (in input units, {:.0f} % of the input's standard "
          "deviation) opposes every motion",
          p[0], 100.0 * p[0] / su);
    case Effect::kLoadDamping: {
      const auto m = dominant_mode(pr.tf);
      return fmt::format(
          "the mode at {:.2f} Hz is damped with a ratio of {:.3f}, not the model's {:.3f}",
          m ? m->first : 0.0, p[0], m ? m->second : 0.0);
    }
    case Effect::kGainChange:
      return fmt::format("the gain is {:.3f} times the model's ({:+.1f} %)", p[0],
                         100.0 * (p[0] - 1.0));
    case Effect::kPeriodicDisturbance:
      return fmt::format(
          "a periodic disturbance at {:.3f} Hz of amplitude {:.3g}, not caused by the input", p[0],
          derived(h, "amplitude"));
    case Effect::kDrift:
      return fmt::format("a slow drift (time scale {:.0f} s, rms {:.3g}) not caused by the input",
                         p[0], derived(h, "drift_rms"));
  }
  return "";
}

// An operating-point step found in the recording (find_level_shift).
std::string level_shift_words(const DiagnoseResult& r) {
  if (!r.level_shift_time_s) return "";
  return fmt::format(
      "The recorded level steps by {:+.4g} at {:.1f} s (an operating-point change, or a gain "
      "that changed with the operating point in it); every model is given that step. ",
      r.level_shift, *r.level_shift_time_s);
}

// A disturbance the location found that no hypothesis makes worth its parameters.
std::string negligible_disturbance(const DiagnoseResult& r) {
  if (!r.location.disturbance || r.hypotheses.empty()) return "";
  const HypothesisFit& h = r.hypotheses.front();
  if (h.name() == "drift")
    return fmt::format(
        " A slow drift of rms {:.3g} ({:.0f} % of the input-driven response, {:.2f} % of the "
        "output's mean level) was detected in the residual: the operating noise of a running "
        "set, not a missing effect (modelling it: validation fit {:.1f} % -> {:.1f} %).",
        derived(h, "drift_rms"), 100.0 * derived(h, "drift_rms") / r.problem.scales.z_std,
        r.problem.y_level != 0.0 ? 100.0 * derived(h, "drift_rms") / std::abs(r.problem.y_level)
                                 : 0.0,
        h.validation_fit_before, h.validation_fit_after);
  return fmt::format(
      " A periodic component was detected in the residual, but modelling it changes the "
      "validation fit only from {:.1f} % to {:.1f} %: not material.",
      h.validation_fit_before, h.validation_fit_after);
}

}  // namespace

std::string explain(const DiagnoseResult& r) {
  const auto& t = r.location.tests;
  if (r.verdict == "none")
    return level_shift_words(r) +
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
  std::string s =
      level_shift_words(r) + where_in_frequency(r.location) + where_in_time_and_level(r);
  if (!t.independent)
    s += fmt::format(
        "The residual is correlated with the input (peak {:.1f} times the 99 % bound at a lag "
        "of {:.2f} s): dynamics are missing. ",
        t.cross_ratio, t.cross_peak_lag_s);
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
  std::string what;
  for (const auto& e : h->effects) {
    if (!what.empty()) what += "; together with that, ";
    what += what_effect_means(e, *h, r.problem);
  }
  s += fmt::format(
      "Diagnosis: {}. Adding it raises the validation fit from {:.1f} % to {:.1f} % "
      "(estimation {:.1f} % to {:.1f} %).",
      what, h->validation_fit_before, h->validation_fit_after, h->fit_before, h->fit_after);
  return s;
}

}  // namespace rig::diagnose
