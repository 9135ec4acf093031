#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/cli/identify_report.hpp"
#include "rig/report/json_out.hpp"

namespace rig::cli {
namespace {

using nlohmann::json;
using report::number_or_null;

json recording_json(const IdentifyContext& ctx) {
  const io::Recording& rec = *ctx.recording;
  json j = {{"path", rec.source},
            {"rows", rec.rows()},
            {"dt_s", rec.dt_s},
            {"dt_source", rec.sampling.dt_source},
            {"input", ctx.input},
            {"output", ctx.output},
            {"has_time_column", rec.sampling.has_time},
            {"jitter_max_s", rec.sampling.jitter_max_s},
            {"jitter_rms_s", rec.sampling.jitter_rms_s},
            {"uniform_sampling", rec.sampling.uniform},
            {"warnings", rec.warnings}};
  j["rows_used"] = {
      {"selection", ctx.rows.mode},
      {"first_row", ctx.rows.first + 1},
      {"count", ctx.rows.count},
      {"of", ctx.rows.total},
      {"phase_code", ctx.rows.phase_code ? json(*ctx.rows.phase_code) : json(nullptr)},
      {"reason", ctx.rows.reason}};
  j["sidecar"] = rec.sidecar.present ? io::to_json(rec.sidecar) : json(nullptr);
  return j;
}

json quality_json(const ident::QualityReport& q) {
  json flags = json::array();
  for (const auto& f : q.flags) {
    flags.push_back({{"name", f.name},
                     {"severity", ident::to_string(f.severity)},
                     {"message", f.message},
                     {"value", number_or_null(f.value)},
                     {"threshold", number_or_null(f.threshold)}});
  }
  json figures = json::object();
  for (const auto& [k, v] : q.figures) figures[k] = number_or_null(v);
  return {{"passed", !q.has_fatal()}, {"flags", flags}, {"figures", figures}};
}

json settings_json(const IdentifyContext& ctx, const ident::IdentifyResult* r) {
  json j = {{"method", ctx.method},
            {"order", ctx.order_arg},
            {"delay", ctx.delay_arg},
            {"lags", ctx.correlator.lags},
            {"zero_index", signal::resolved_zero_index(ctx.correlator)},
            {"skip", ctx.correlator.skip},
            {"correlator", signal::to_string(ctx.correlator.kind)},
            {"estimation_fraction", ctx.estimation_fraction}};
  if (r) {
    j["summary"] = r->settings;
    j["std_error_method"] = r->std_error_method;
  }
  return j;
}

json structure_json(const ident::Structure& s) {
  return {{"name", s.name()},
          {"n", s.order.n},
          {"m", s.order.m},
          {"delay_estimated", s.delay_estimated},
          {"method", ident::to_string(s.method)},
          {"parameters", s.parameters()}};
}

json fit_table_json(const ident::StructureTable& t) {
  double aic0 = INFINITY, bic0 = INFINITY;
  for (const auto& f : t.rows)
    if (f.ok) aic0 = std::min(aic0, f.aic), bic0 = std::min(bic0, f.bic);
  json rows = json::array();
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const ident::StructureFit& f = t.rows[i];
    json row = structure_json(f.structure);
    row["ok"] = f.ok;
    row["error"] = f.ok ? json(nullptr) : json(f.error);
    row["delay_s"] = f.ok ? number_or_null(f.model.delay_s) : json(nullptr);
    row["estimation_fit_pct"] = number_or_null(f.estimation_fit_pct);
    row["validation_fit_pct"] = number_or_null(f.validation_fit_pct);
    row["aic"] = number_or_null(f.aic);
    row["bic"] = number_or_null(f.bic);
    row["delta_aic"] = number_or_null(f.aic - aic0);
    row["delta_bic"] = number_or_null(f.bic - bic0);
    row["adequate"] = f.adequate;
    row["selected"] = static_cast<int>(i) == t.chosen;
    rows.push_back(row);
  }
  return {{"rule", t.rule}, {"chosen", t.chosen}, {"best", t.best}, {"rows", rows}};
}

json validation_json(const ident::ValidationData& v) {
  const ident::ResidualTests& t = v.residuals;
  return {{"data", v.what},
          {"samples", v.y.size()},
          {"fit_pct", number_or_null(v.fit_pct)},
          {"residual_tests",
           {{"max_lag_s",
             t.lags_s.size() ? number_or_null(t.lags_s(t.lags_s.size() - 1)) : json(nullptr)},
            {"whiteness_ratio", number_or_null(t.whiteness_ratio)},
            {"white", t.white},
            {"cross_ratio", number_or_null(t.cross_ratio)},
            {"cross_threshold", number_or_null(t.cross_threshold)},
            {"cross_peak_lag_s", number_or_null(t.cross_peak_lag_s)},
            {"independent", t.independent}}}};
}

json band_json(const ident::IdentifyResult& r) {
  double db = 0.0, deg = 0.0;
  for (const auto& b : r.band) db = std::max(db, b.sd_db), deg = std::max(deg, b.sd_deg);
  return {{"method", "asymptotic covariance (frf_uncertainty), simultaneous 95 %"},
          {"factor", number_or_null(r.band_factor)},
          {"points", r.band.size()},
          {"max_sd_db", number_or_null(db)},
          {"max_sd_deg", number_or_null(deg)}};
}

json records_json(const IdentifyContext& ctx) {
  json out = json::array();
  if (!ctx.records) return out;
  for (const IdentifyRecord& r : *ctx.records) {
    out.push_back(
        {{"path", r.rec.source},
         {"role", r.role},
         {"rows", r.rec.rows()},
         {"rows_reason", r.rows.reason},
         {"y_sampled_after_s",
          r.rec.sidecar.y_sampled_after_s ? json(*r.rec.sidecar.y_sampled_after_s) : json(nullptr)},
         {"quality_passed", !r.quality.has_fatal()}});
  }
  return out;
}

json result_json(const ident::IdentifyResult& r) {
  json params = json::array();
  for (const auto& p : r.parameters) {
    params.push_back({{"name", p.name},
                      {"value", number_or_null(p.value)},
                      {"std_error", number_or_null(p.std_error)}});
  }
  json derived = nullptr;
  if (r.derived.valid) {
    derived = {{"gain", number_or_null(r.derived.gain)},
               {"gain_std", number_or_null(r.derived.gain_std)},
               {"fn_hz", number_or_null(r.derived.fn_hz)},
               {"fn_hz_std", number_or_null(r.derived.fn_hz_std)},
               {"zeta", number_or_null(r.derived.zeta)},
               {"zeta_std", number_or_null(r.derived.zeta_std)}};
  }
  return {
      {"model",
       {{"num", report::to_json_array(r.model.num)},
        {"den", report::to_json_array(r.model.den)},
        {"delay_s", number_or_null(r.model.delay_s)},
        {"order", {{"n", r.order.n}, {"m", r.order.m}}},
        {"dc_gain", number_or_null(r.model.dc_gain())},
        {"stable", r.model.is_stable()}}},
      {"parameters", params},
      {"delay",
       {{"value_s", number_or_null(r.delay_s)}, {"std_error_s", number_or_null(r.delay_std_s)}}},
      {"derived", derived},
      {"structure", structure_json(r.structure)},
      {"fit_table", fit_table_json(r.table)},
      {"validation_fit_pct", number_or_null(r.validation_fit_pct)},
      {"validation", validation_json(r.validation)},
      {"bode_band", band_json(r)},
      {"condition_number", number_or_null(r.condition_number)}};
}

}  // namespace

json identify_report_json(const IdentifyContext& ctx, const ident::QualityReport& quality,
                          const ident::IdentifyResult* result) {
  json j = {{"command", "identify"},
            {"status", result                 ? "ok"
                       : ctx.no_model.empty() ? "data_quality_failed"
                                              : "no_stable_model"},
            {"exit_code", result ? 0 : 1},
            {"recording", recording_json(ctx)},
            {"settings", settings_json(ctx, result)},
            {"quality", quality_json(quality)},
            {"records", records_json(ctx)},
            {"timing",
             {{"refers_to", ctx.timing_correction_s ? "plant" : "rows"},
              {"correction_s",
               ctx.timing_correction_s ? json(*ctx.timing_correction_s) : json(nullptr)}}}};
  if (!ctx.no_model.empty()) j["message"] = ctx.no_model;
  if (result) {
    j.update(result_json(*result));
    j["files"] = {{"model", "model.json"}, {"report_html", "report.html"}};
  } else {
    j["files"] = {{"report_html", "report.html"}};
  }
  return j;
}

model::ModelFile identify_model_file(const IdentifyContext& ctx, const ident::IdentifyResult& r) {
  model::ModelFile m;
  m.tf = r.model;
  m.fit_percent = r.validation_fit_pct;
  m.input = ctx.input;
  m.output = ctx.output;
  const auto& units = ctx.recording->sidecar.units;
  if (units.count(ctx.input) && units.count(ctx.output)) {
    m.units = {{"input", units.at(ctx.input)}, {"output", units.at(ctx.output)}};
  }
  nlohmann::json params = nlohmann::json::array();
  for (const auto& p : r.parameters) {
    params.push_back({{"name", p.name},
                      {"value", number_or_null(p.value)},
                      {"std_error", number_or_null(p.std_error)}});
  }
  m.extra["parameters"] = params;
  m.extra["method"] = ident::to_string(r.structure.method);
  m.extra["structure"] = r.structure.name();
  // The dead time refers to the plant (sidecar y_sampled_after_s), as rig commission's.
  if (ctx.timing_correction_s) m.extra["timing"] = "plant";
  m.extra["source"] = ctx.recording->source;
  return m;
}

std::string polynomial_text(const Eigen::VectorXd& c) {
  std::string out;
  const Eigen::Index n = c.size() - 1;
  for (Eigen::Index i = 0; i <= n; ++i) {
    const double v = c[i];
    if (v == 0.0 && n > 0) continue;
    const Eigen::Index power = n - i;
    if (!out.empty())
      out += v < 0 ? " - " : " + ";
    else if (v < 0)
      out += "-";
    out += fmt::format("{:.4g}", std::abs(v));
    if (power >= 1) out += " s";
    if (power >= 2) out += fmt::format("^{}", power);
  }
  return out.empty() ? "0" : out;
}

}  // namespace rig::cli
