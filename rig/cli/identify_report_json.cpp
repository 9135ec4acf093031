#include <fmt/format.h>

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

json result_json(const ident::IdentifyResult& r) {
  json params = json::array();
  for (const auto& p : r.parameters) {
    params.push_back({{"name", p.name},
                      {"value", number_or_null(p.value)},
                      {"std_error", number_or_null(p.std_error)}});
  }
  json orders = json::array();
  for (const auto& o : r.order_table) {
    orders.push_back({{"n", o.order.n},
                      {"m", o.order.m},
                      {"fit_pct", number_or_null(o.fit_pct)},
                      {"validation_fit_pct", number_or_null(o.validation_fit_pct)},
                      {"score", number_or_null(o.score)},
                      {"delay_s", number_or_null(o.delay_s)},
                      {"selected", o.order == r.order}});
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
      {"order_table", orders},
      {"validation_fit_pct", number_or_null(r.validation_fit_pct)},
      {"condition_number", number_or_null(r.condition_number)}};
}

}  // namespace

json identify_report_json(const IdentifyContext& ctx, const ident::QualityReport& quality,
                          const ident::IdentifyResult* result) {
  json j = {{"command", "identify"},
            {"status", result ? "ok" : "data_quality_failed"},
            {"exit_code", result ? 0 : 1},
            {"recording", recording_json(ctx)},
            {"settings", settings_json(ctx, result)},
            {"quality", quality_json(quality)}};
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
  m.extra["method"] = ctx.method;
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
