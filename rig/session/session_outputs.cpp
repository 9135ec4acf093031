#include "rig/session/session_outputs.hpp"

#include <fmt/format.h>

#include "rig/model/frf_file.hpp"
#include "rig/model/model_file.hpp"
#include "rig/report/json_out.hpp"

namespace rig::session {
namespace {

using nlohmann::json;
using report::number_or_null;

json parameters_json(const std::vector<ident::ParameterEstimate>& params) {
  json a = json::array();
  for (const auto& p : params) {
    a.push_back({{"name", p.name},
                 {"value", number_or_null(p.value)},
                 {"std_error", number_or_null(p.std_error)}});
  }
  return a;
}

json derived_json(const ident::DerivedFigures& d) {
  if (!d.valid) return nullptr;
  return {{"gain_kw_per_pct", number_or_null(d.gain)},
          {"gain_std", number_or_null(d.gain_std)},
          {"fn_hz", number_or_null(d.fn_hz)},
          {"fn_hz_std", number_or_null(d.fn_hz_std)},
          {"zeta", number_or_null(d.zeta)},
          {"zeta_std", number_or_null(d.zeta_std)}};
}

json compare_json(const std::optional<fra::CompareResult>& c) {
  if (!c) return nullptr;
  json rows = json::array();
  for (const auto& r : c->rows) {
    rows.push_back({{"freq_hz", r.freq_hz},
                    {"mag_error_db", number_or_null(r.mag_error_db)},
                    {"phase_error_deg", number_or_null(r.phase_error_deg)},
                    {"checked", r.checked},
                    {"pass", r.pass}});
  }
  return {{"verdict", fra::to_string(c->verdict)},
          {"checked", c->checked},
          {"failed", c->failed},
          {"max_abs_mag_error_db", number_or_null(c->max_abs_mag_error_db)},
          {"max_abs_phase_error_deg", number_or_null(c->max_abs_phase_error_deg)},
          {"summary", c->summary},
          {"rows", rows}};
}

json frf_json(const std::vector<model::FrfPoint>& frf) {
  json a = json::array();
  for (const auto& p : frf) {
    a.push_back({{"freq_hz", p.freq_hz},
                 {"mag", number_or_null(p.mag)},
                 {"phase_deg", number_or_null(p.phase_deg)},
                 {"coherence", number_or_null(p.coherence)},
                 {"valid", p.valid}});
  }
  return a;
}

json shaped_json(const std::optional<ShapedDesign>& d) {
  if (!d) return nullptr;
  return {{"lines", d->lines},
          {"from_hz", d->f_lo_hz},
          {"to_hz", d->f_hi_hz},
          {"period_s", static_cast<double>(d->period_pct.size()) * d->dt_s},
          {"std_pct", d->std_pct},
          {"input_crest", d->input_crest},
          {"output_crest", d->output_crest},
          {"predicted_peak_kw", d->predicted_peak_kw},
          {"limited_by_clamp", d->limited_by_clamp},
          {"pilot_model",
           {{"num", report::to_json_array(d->pilot_model.num)},
            {"den", report::to_json_array(d->pilot_model.den)},
            {"delay_s", d->pilot_model.delay_s}}}};
}

json candidates_json(const std::optional<ident::OrderChoice>& choice) {
  json a = json::array();
  if (!choice) return a;
  for (const auto& c : choice->candidates) {
    json e = {{"order", {c.order.n, c.order.m}}, {"ok", c.ok}, {"error", c.error}};
    if (c.ok) {
      e["num"] = report::to_json_array(c.model.num);
      e["den"] = report::to_json_array(c.model.den);
      e["delay_s"] = c.model.delay_s;
      e["fit_pct"] = number_or_null(c.fit_pct);
      e["band_db95"] = number_or_null(c.width.db);
      e["band_deg95"] = number_or_null(c.width.deg);
      if (c.order.n == 2) {
        // The thesis's q-form: 1 / (q2 s^2 + q1 s + q0) with b0 = 1, and K, fn, zeta.
        const model::TransferFunction q = ident::normalise(c.model, ident::Normalisation::kUnitB0);
        e["q_form"] = {{"q2", q.den(0)}, {"q1", q.den(1)}, {"q0", q.den(2)}};
        e["derived"] = derived_json(ident::derived_figures(c.model, Eigen::MatrixXd()));
      }
    }
    e["chosen"] = choice->best() == &c;
    a.push_back(e);
  }
  return a;
}

json history_json(const std::vector<BlockEstimate>& history) {
  json a = json::array();
  for (const auto& e : history) {
    a.push_back({{"block", e.block},
                 {"t_s", e.t_s},
                 {"ok", e.ok},
                 {"error", e.error},
                 {"parameters", parameters_json(e.parameters)},
                 {"derived", derived_json(e.derived)},
                 {"delay_s", number_or_null(e.delay_s)},
                 {"order", {e.order.n, e.order.m}},
                 {"num", e.ok ? json(std::vector<double>(e.model.num.begin(), e.model.num.end()))
                              : json(nullptr)},
                 {"den", e.ok ? json(std::vector<double>(e.model.den.begin(), e.model.den.end()))
                              : json(nullptr)},
                 {"band_db95", number_or_null(e.band_db95)},
                 {"band_deg95", number_or_null(e.band_deg95)},
                 {"fit_pct", number_or_null(e.fit_pct)}});
  }
  return a;
}

json config_json(const TestConfig& c) {
  return {{"source", c.source},
          {"sample_rate_hz", c.link.sample_rate_hz},
          {"lockstep_ticks", c.link.lockstep_ticks},
          {"rated_power_kw", c.plant.rated_power_kw},
          {"band_pct", c.safety.band_pct},
          {"band_override", c.safety.allow_band_above_3pct && c.safety.band_pct > kStandardBandPct},
          {"clamp_pct", c.safety.clamp_pct},
          {"excitation", to_string(c.excitation.type)},
          {"bandwidth_hz", c.excitation.bandwidth_hz},
          {"excitation_seed", c.excitation.seed},
          {"ac_coupling_rc_s", c.excitation.ac_coupling_rc_s},
          {"order", {c.mmfm.order_n, c.mmfm.order_m}},
          {"lags", c.mmfm.lags},
          {"block_size", c.mmfm.block_size},
          {"skip", c.mmfm.skip},
          {"correlator", c.mmfm.correlator},
          {"averaging", c.mmfm.averaging},
          {"auto_order", c.mmfm.auto_order},
          {"target_db", c.mmfm.target_db},
          {"target_deg", c.mmfm.target_deg},
          {"sweep",
           {{"from_hz", c.sweep.from_hz},
            {"to_hz", c.sweep.to_hz},
            {"points", c.sweep.points},
            {"enabled", c.sweep.enabled}}},
          {"compare",
           {{"from_hz", c.compare.from_hz},
            {"to_hz", c.compare.to_hz},
            {"mag_tol_db", c.compare.mag_tol_db},
            {"phase_tol_deg", c.compare.phase_tol_deg}}}};
}

// Realtime: lateness of each cycle's start against its schedule and overruns; lockstep: the
// wall time per exchange (docs/test-file.md, `loop_timing`).
json loop_timing_json(const std::optional<LoopTimingSummary>& t) {
  if (!t) return nullptr;
  json j = {{"mode", t->mode},
            {"period_ms", t->period_ms},
            {"cycles", t->cycles},
            {"exchange_p50_ms", t->exchange_p50_ms},
            {"exchange_p99_ms", t->exchange_p99_ms},
            {"exchange_max_ms", t->exchange_max_ms},
            {"exchange_mean_ms", t->exchange_mean_ms},
            {"histogram",
             {{"of", t->mode == "realtime" ? "jitter" : "exchange"},
              {"bin_ms", t->histogram.bin_ms},
              {"counts", t->histogram.counts}}}};
  if (t->mode == "realtime") {
    j["jitter_p50_ms"] = t->jitter_p50_ms;
    j["jitter_p99_ms"] = t->jitter_p99_ms;
    j["jitter_max_ms"] = t->jitter_max_ms;
    j["jitter_mean_ms"] = t->jitter_mean_ms;
    j["overruns"] = t->overruns;
    j["realtime_priority"] = t->realtime_priority;
    j["cpu_latency_held"] = t->cpu_latency_held;
    j["slips"] = t->slips;
    j["slip_total_ms"] = t->slip_total_ms;
  }
  return j;
}

}  // namespace

json report_json(const SessionData& d) {
  json j;
  j["command"] = d.command;
  j["exit_code"] = d.exit_code;
  j["outcome"] = d.outcome;
  j["link"] = d.link_uri;
  j["preset"] = d.preset;
  j["plant_seed"] = d.plant_seed ? json(*d.plant_seed) : json(nullptr);
  j["config"] = config_json(d.config);
  if (d.steady) {
    j["steady_state"] = {{"ok", d.steady->ok},
                         {"p0_kw", d.steady->p0_kw},
                         {"noise_pct", d.steady->noise_pct},
                         {"drift_pct", d.steady->drift_pct},
                         {"duration_s", d.steady->duration_s},
                         {"reason", d.steady->reason}};
  }
  if (d.pilot) {
    j["pilot"] = {{"ok", d.pilot->ok},
                  {"gain_kw_per_pct", d.pilot->gain_kw_per_pct},
                  {"applied_std_pct", d.pilot->applied_std_pct},
                  {"planned_std_pct", d.pilot->planned_std_pct},
                  {"predicted_peak_kw", d.pilot->predicted_peak_kw},
                  {"band_kw", d.pilot->band_kw},
                  {"limited_by_clamp", d.pilot->limited_by_clamp}};
  }
  j["excitation"] = {
      {"std_pct", d.excitation.planned_std_pct},
      {"planned_std_pct", d.excitation.planned_std_pct},
      {"applied_std_pct", d.excitation.applied_std_pct},
      {"applied_fraction", d.excitation.planned_std_pct > 0.0
                               ? json(d.excitation.applied_std_pct / d.excitation.planned_std_pct)
                               : json(nullptr)},
      {"duration_s", d.excitation.duration_s},
      {"stop_reason", d.excitation.stop_reason},
      {"quality_flags", d.excitation.quality_flags},
      {"type", d.excitation.type},
      {"shaped", shaped_json(d.excitation.shaped)}};
  j["model_written"] = d.excitation.mmfm.has_value() && d.exit_code == kExitOk;
  j["model_rejected"] = d.model_rejected;
  j["activation"] = d.activation ? json{{"acknowledged", d.activation->acknowledged},
                                        {"status", d.activation->status},
                                        {"waited_s", d.activation->waited_s}}
                                 : json(nullptr);
  j["ramp_down"] = {{"attempted", d.ramp_down.attempted},
                    {"cleared", d.ramp_down.cleared},
                    {"reconnects", d.ramp_down.reconnects},
                    {"error", d.ramp_down.error}};
  if (d.excitation.mmfm) {
    const auto& m = *d.excitation.mmfm;
    j["mmfm"] = {{"num", report::to_json_array(m.model.num)},
                 {"den", report::to_json_array(m.model.den)},
                 {"delay_s", m.delay_s},
                 {"delay_std_s", number_or_null(m.delay_std_s)},
                 {"parameters", parameters_json(m.parameters)},
                 {"derived", derived_json(m.derived)},
                 {"condition_number", number_or_null(m.condition_number)},
                 {"correlation_fit_pct", number_or_null(m.correlation_fit_pct)},
                 {"candidates", candidates_json(d.excitation.order_choice)}};
    if (d.excitation.order_choice && d.excitation.order_choice->best()) {
      const auto& b = *d.excitation.order_choice->best();
      j["mmfm"]["order"] = {b.order.n, b.order.m};
      j["mmfm"]["band_db95"] = number_or_null(b.width.db);
      j["mmfm"]["band_deg95"] = number_or_null(b.width.deg);
    }
  } else {
    j["mmfm"] = nullptr;
  }
  j["mmfm_error"] = d.excitation.mmfm_error;
  j["history"] = history_json(d.excitation.history);
  j["sweep"] = frf_json(d.sweep);
  j["compare"] = {{"sweep", compare_json(d.compare_sweep)}, {"h1", compare_json(d.compare_h1)}};
  j["safety"] = {{"band_pct", d.config.safety.band_pct},
                 {"band_override", d.config.safety.band_pct > kStandardBandPct},
                 {"max_abs_deviation_pct", d.max_abs_deviation_pct},
                 {"trip", d.trip ? json{{"cause", to_string(d.trip->cause)},
                                        {"text", d.trip->text},
                                        {"tick", d.trip->tick}}
                                 : json(nullptr)}};
  json events = json::array();
  for (const auto& e : d.events)
    events.push_back({{"t_s", e.t_s}, {"kind", e.kind}, {"text", e.text}});
  j["events"] = events;
  j["timing"] = {{"test_time_s", d.test_time_s}, {"wall_time_s", d.wall_time_s}};
  j["loop_timing"] = loop_timing_json(d.loop_timing);
  return j;
}

namespace {

template <class Fn>
bool attempt(const char* what, Fn fn) {
  try {
    fn();
    return true;
  } catch (const std::exception& e) {
    fmt::print(stderr, "rig: could not write {}: {}\n", what, e.what());
    return false;
  }
}

}  // namespace

bool write_outputs(const SessionData& d, const std::filesystem::path& out) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  // A model only from a run that passed: a failed run writes none (DESIGN.md section 8).
  if (d.excitation.mmfm && d.exit_code == kExitOk) {
    attempt("model.json", [&] {
      model::ModelFile m;
      m.tf = d.excitation.mmfm->model;
      m.tf.delay_s = d.excitation.mmfm->delay_s;
      m.input.assign(1, 'u');
      m.output.assign(1, 'y');
      m.units = "kW/%";
      m.extra["parameters"] = parameters_json(d.excitation.mmfm->parameters);
      m.extra["method"] = "mmfm";
      // Its dead time refers to the plant: the rig's sample timing (bias held for a sample,
      // power read a sample after the write in lockstep) is taken out (docs/decisions.md).
      m.extra["timing"] = "plant";
      model::write_model(out / "model.json", m);
    });
  }
  if (!d.sweep.empty()) attempt("sweep.csv", [&] { model::write_frf(out / "sweep.csv", d.sweep); });
  if (!d.excitation.h1.empty())
    attempt("h1.csv", [&] { model::write_frf(out / "h1.csv", d.excitation.h1); });
  bool ok =
      attempt("report.json", [&] { report::write_json_file(out / "report.json", report_json(d)); });
  ok = attempt("report.html", [&] { write_report_html(d, out / "report.html"); }) && ok;
  return ok;
}

}  // namespace rig::session
