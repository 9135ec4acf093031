#include <string>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/report_out.hpp"
#include "rig/report/json_out.hpp"

namespace rig::diagnose {
namespace {

using nlohmann::json;
using report::number_or_null;

json hypothesis_json(const HypothesisFit& h, const Problem& pr) {
  json params = json::object(), effects = json::array();
  for (const auto& e : h.effects) {
    const auto specs = parameter_specs(e.effect, pr.scales);
    json p = json::object();
    for (std::size_t i = 0; i < acting_params(e); ++i) {
      p[specs[i].name] = number_or_null(e.params[i]);
      params[h.effects.size() > 1 ? std::string(to_string(e.effect)) + "." + specs[i].name
                                  : specs[i].name] = number_or_null(e.params[i]);
    }
    const auto place = place_specs(e.place, pr.scales);
    for (std::size_t i = 0; i < e.place_params.size(); ++i) {
      p[place[i].name] = number_or_null(e.place_params[i]);
      params[h.effects.size() > 1 ? std::string(to_string(e.effect)) + "." + place[i].name
                                  : place[i].name] = number_or_null(e.place_params[i]);
    }
    effects.push_back(
        {{"effect", to_string(e.effect)}, {"place", to_string(e.place)}, {"params", p}});
  }
  json derived = json::object();
  for (const auto& [k, v] : h.derived) derived[k] = number_or_null(v);
  return {{"effect", h.name()},
          {"effects", effects},
          {"params", params},
          {"derived", derived},
          {"fit_before", number_or_null(h.fit_before)},
          {"fit_after", number_or_null(h.fit_after)},
          {"validation_fit_before", number_or_null(h.validation_fit_before)},
          {"validation_fit_after", number_or_null(h.validation_fit_after)},
          {"score", number_or_null(h.score)},
          {"active_span_s",
           {static_cast<double>(h.active_from) * pr.dt_s,
            static_cast<double>(h.active_to < 0 ? pr.u.size() : h.active_to) * pr.dt_s}},
          {"parameters", h.parameter_count()},
          {"evaluations", h.evaluations}};
}

// An operating-point step taken out of the recording and the step-gain test at it.
json level_shift_json(const DiagnoseResult& r) {
  if (!r.level_shift_time_s) return nullptr;
  json j = {{"time_s", *r.level_shift_time_s}, {"size", r.level_shift}};
  if (const StepGain& g = r.location.step_gain; g.tested)
    j["step_gain"] = {{"level_ratio", g.level_ratio},
                      {"gain_change", g.change},
                      {"gain_change_sd", g.sd},
                      {"z", g.z},
                      {"log_likelihood_ratio", g.log_likelihood_ratio},
                      {"fires", g.fires},
                      {"decisive", g.decisive}};
  return j;
}

// The coupling test (locate.hpp CouplingTest); null when the record is too short for it.
json coupling_json(const CouplingTest& c) {
  if (!c.tested) return nullptr;
  return {{"rc_s", c.rc_s},
          {"coefficient", c.beta},
          {"coefficient_sd", c.sd},
          {"log_likelihood_ratio", c.log_likelihood_ratio},
          {"fires", c.fires}};
}

// The recorded bus frequency and what became of it (bus_frequency.hpp); null without one.
json bus_frequency_json(const DiagnoseResult& r) {
  if (!r.bus_frequency) return nullptr;
  const BusFrequencyShare& b = *r.bus_frequency;
  return {{"used", b.used},
          {"bias_coherence", b.bias_coherence},
          {"frequency_rms_hz", b.frequency_rms_hz},
          {"share_rms", b.share_rms},
          {"residual_share", b.residual_share},
          {"input_per_hz", b.input_per_hz},
          {"input_per_hz_se", b.input_per_hz_se},
          {"droop_pct", b.droop_pct},
          {"referred", b.referred},
          {"event_s",
           b.event_at > 0 ? json(static_cast<double>(b.event_at) * r.problem.dt_s) : json(nullptr)},
          {"event_step", b.event_step},
          {"operating_point_move", r.operating_point_move.has_value()},
          {"sign_z_sides", r.operating_point_move ? json::array({r.operating_point_move->sign_z[0],
                                                                 r.operating_point_move->sign_z[1]})
                                                  : json(nullptr)},
          {"note", b.note}};
}

json location_json(const DiagnoseResult& r) {
  const Location& loc = r.location;
  json windows = json::array();
  for (const auto& w : loc.windows)
    windows.push_back({{"from_s", w.from_s},
                       {"to_s", w.to_s},
                       {"rms_ratio", w.rms_ratio},
                       {"found_by", "residual level"}});
  const HypothesisFit* h = r.chosen();
  const Eigen::Index n = r.problem.u.size();
  if (windows.empty() && h && (h->active_from > 0 || (h->active_to >= 0 && h->active_to < n)))
    windows.push_back(
        {{"from_s", static_cast<double>(h->active_from) * r.problem.dt_s},
         {"to_s", static_cast<double>(h->active_to < 0 ? n : h->active_to) * r.problem.dt_s},
         {"rms_ratio", nullptr},
         {"found_by", "change point of the fitted effect's gain"}});
  json levels = json::array();
  for (const auto& b : loc.amp.by_level)
    levels.push_back({{"level", b.level}, {"gain", b.gain}, {"gain_std", b.gain_std}});
  json band = loc.freq.band_hz ? json::array({loc.freq.band_hz->first, loc.freq.band_hz->second})
                               : json(nullptr);
  return {{"band_hz", band},
          {"timing_nuisance_s", r.timing_nuisance_s},
          {"time_windows", windows},
          {"level_shift", level_shift_json(r)},
          {"coupling", coupling_json(loc.coupling)},
          {"amplitude_dependent", loc.amp.fails()},
          {"amplitude",
           {{"by_level", levels},
            {"level_chi2", loc.amp.level_chi2},
            {"output_level_chi2", loc.amp.output_level_chi2},
            {"output_level_dependent", loc.amp.output_level_dependent},
            {"level_dependent", loc.amp.amplitude_dependent},
            {"sign_z", loc.amp.sign_z},
            {"sign_dependent", loc.amp.sign_dependent},
            {"direction_z", loc.amp.direction_z},
            {"direction_dependent", loc.amp.direction_dependent},
            {"output_direction_z", loc.amp.output_direction_z},
            {"direction_beyond_lag_z", loc.amp.direction_beyond_lag_z},
            {"direction_beyond_lag_dependent", loc.amp.direction_beyond_lag_dependent},
            {"two_level_input", loc.amp.two_level_input}}},
          {"residual_tests",
           {{"whiteness_ratio", loc.tests.whiteness_ratio},
            {"white", loc.tests.white},
            {"cross_ratio", loc.tests.cross_ratio},
            {"cross_threshold", loc.tests.cross_threshold},
            {"cross_peak_lag_s", loc.tests.cross_peak_lag_s},
            {"independent", loc.tests.independent},
            {"halves", json::array({{{"cross_ratio", loc.halves[0].cross_ratio},
                                     {"cross_threshold", loc.halves[0].cross_threshold},
                                     {"independent", loc.halves[0].independent}},
                                    {{"cross_ratio", loc.halves[1].cross_ratio},
                                     {"cross_threshold", loc.halves[1].cross_threshold},
                                     {"independent", loc.halves[1].independent}}})},
            {"half_dependent", loc.half_dependent}}},
          {"disturbances",
           {{"periodic", loc.dist.periodic},
            {"line_freq_hz", loc.dist.line_freq_hz},
            {"line_ratio", loc.dist.line_ratio},
            {"drift", loc.dist.drift},
            {"drift_ratio", loc.dist.drift_ratio}}},
          {"output_clip", loc.clip.side == 0 ? json(nullptr)
                                             : json{{"side", loc.clip.side > 0 ? "top" : "bottom"},
                                                    {"level", loc.clip.level},
                                                    {"samples", loc.clip.samples}}},
          {"input_mismatch", loc.input_mismatch},
          {"input_tests_behind_drift", loc.behind_drift},
          {"coherence_threshold", loc.freq.coherence_threshold},
          {"input_band_hz", loc.freq.input_band_hz},
          {"active_span_s",
           {static_cast<double>(r.problem.active_from) * r.problem.dt_s,
            static_cast<double>(r.problem.active_to) * r.problem.dt_s}}};
}

}  // namespace

nlohmann::json report_json(const DiagnoseResult& r, const ReportContext& c) {
  json hyps = json::array();
  for (const auto& h : r.hypotheses) hyps.push_back(hypothesis_json(h, r.problem));
  return {{"command", "diagnose"},
          {"recording", c.recording},
          {"model", c.model},
          {"input", c.input_column},
          {"output", c.output_column},
          {"verdict", r.verdict},
          {"explanation", r.explanation},
          {"chosen", r.chosen_index >= 0 ? json(r.chosen_index) : json(nullptr)},
          {"alternative", r.alternative_index >= 0 ? json(r.alternative_index) : json(nullptr)},
          {"hypotheses", hyps},
          {"location", location_json(r)},
          {"fit_before", number_or_null(r.fit_before_pct)},
          {"validation_fit_before", number_or_null(r.validation_fit_before_pct)},
          {"samples", r.problem.u.size()},
          {"dt_s", r.problem.dt_s},
          {"blocks", r.blocks},
          {"warmup_s", static_cast<double>(r.warmup) * r.problem.dt_s},
          {"output_coupling_rc_s",
           r.problem.output_rc_s ? json(*r.problem.output_rc_s) : json(nullptr)},
          {"bus_frequency", bus_frequency_json(r)},
          {"elapsed_s", r.elapsed_s},
          {"augmented_model", "augmented_model.json"}};
}

model::ModelFile augmented_model(const DiagnoseResult& r, const model::ModelFile& baseline) {
  model::ModelFile m = baseline;
  m.cov.reset();
  json aug = json::array();
  if (const HypothesisFit* h = r.chosen()) {
    m.tf = h->tf;
    m.fit_percent = h->validation_fit_after;
    for (const auto& e : h->effects) {
      const auto specs = parameter_specs(e.effect, r.problem.scales);
      json p = json::object();
      for (std::size_t i = 0; i < acting_params(e); ++i) p[specs[i].name] = e.params[i];
      const auto place = place_specs(e.place, r.problem.scales);
      for (std::size_t i = 0; i < e.place_params.size(); ++i) p[place[i].name] = e.place_params[i];
      // On the governor's error even a linear effect (a dead time in the loop) stays out of
      // the tf: the place says how it acts.
      const bool placed = kind_of(e.effect) == EffectKind::kInputNonlinearity || on_error(e.place);
      const char* where = placed ? place_acts(e.place)
                          : kind_of(e.effect) == EffectKind::kFeedback
                              ? "output feedback around the tf's rational part"
                          : kind_of(e.effect) == EffectKind::kDisturbance ? "added to the output"
                                                                          : "in num/den/delay_s";
      aug.push_back({{"effect", to_string(e.effect)}, {"params", p}, {"acts", where}});
    }
    json derived = json::object();
    for (const auto& [k, v] : h->derived) derived[k] = report::number_or_null(v);
    m.extra["augmentation_derived"] = derived;
  }
  m.extra["augmentation"] = aug;
  // The sampling convention's shift of the dead time, within +-dt/2 (not an effect).
  m.extra["timing_nuisance_s"] = r.timing_nuisance_s;
  m.extra["baseline"] = {{"num", report::to_json_array(baseline.tf.num)},
                         {"den", report::to_json_array(baseline.tf.den)},
                         {"delay_s", baseline.tf.delay_s}};
  // The recorded output's clip, which the model's output is compared through (min/max).
  if (const OutputClip& c = r.problem.output_clip; c.side != 0)
    m.extra["output_clip"] = {{"side", c.side > 0 ? "top" : "bottom"}, {"level", c.level}};
  m.extra["diagnose_verdict"] = r.verdict;
  return m;
}

}  // namespace rig::diagnose
