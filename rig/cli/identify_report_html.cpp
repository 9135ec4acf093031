#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/cli/identify_report.hpp"
#include "rig/cli/identify_report_sections.hpp"
#include "rig/report/bode_chart.hpp"
#include "rig/report/html_report.hpp"
#include "rig/report/json_out.hpp"

namespace rig::cli {
namespace {

using report::Chart;
using report::HtmlReport;

std::vector<double> lags_s(const signal::Correlation& c) {
  std::vector<double> out;
  for (Eigen::Index i = 0; i < c.size(); ++i) out.push_back(c.lag_s(i));
  return out;
}

std::string records_text(const IdentifyContext& ctx) {
  if (!ctx.records || ctx.records->size() < 2)
    return "one: estimated on its first part, validated on the rest";
  std::string out;
  for (const IdentifyRecord& r : *ctx.records)
    out += (out.empty() ? "" : "; ") + r.role + " " + r.rec.source;
  return out;
}

void quality_block(HtmlReport& page, const ident::QualityReport& q) {
  page.section("Data-quality checks");
  if (q.flags.empty()) page.note(report::Tone::kOk, "All data-quality checks passed.");
  for (const auto& f : q.flags) {
    page.note(f.severity == ident::Severity::kFatal ? report::Tone::kFatal : report::Tone::kWarning,
              fmt::format("{} ({}): {}", f.name, ident::to_string(f.severity), f.message));
  }
}

void correlation_charts(HtmlReport& page, const signal::Correlation& ruu,
                        const signal::Correlation& ryu, const signal::Correlation* model_ryu) {
  page.section("Correlation functions");
  page.chart({"Input auto-correlation r_uu",
              "lag (s)",
              "r_uu",
              lags_s(ruu),
              {{"r_uu", report::to_std_vector(ruu.r)}}});
  Chart cross{"Cross-correlation r_yu: measured and model",
              "lag (s)",
              "r_yu",
              lags_s(ryu),
              {{"measured", report::to_std_vector(ryu.r)}}};
  if (model_ryu && model_ryu->size() == ryu.size()) {
    cross.series.push_back({"model", report::to_std_vector(model_ryu->r), "#d62728", true});
  }
  page.chart(cross);
}

// Blackman-Tukey estimate H = S_yu / S_uu from the correlations (Bartlett lag window),
// where the input carries at least 1 % of its peak power; NaN elsewhere.
// delay_s: added to the estimate's dead time (the rows' timing to the plant's).
std::vector<std::complex<double>> correlation_frf(const ident::IdentifyResult& r,
                                                  const std::vector<double>& f, double delay_s) {
  auto spectrum = [](const signal::Correlation& c, double fh) {
    const double half = double(std::max(c.negative_lags(), c.positive_lags()) + 1);
    std::complex<double> s = 0.0;
    for (Eigen::Index i = 0; i < c.size(); ++i) {
      const double w = 1.0 - std::abs(double(i - c.zero_index)) / half;
      s += w * c.r[i] * std::exp(std::complex<double>(0.0, -2 * M_PI * fh * c.lag_s(i)));
    }
    return s;
  };
  std::vector<std::complex<double>> suu, h;
  double peak = 0.0;
  for (double fh : f) {
    suu.push_back(spectrum(r.ruu, fh));
    peak = std::max(peak, std::abs(suu.back()));
  }
  for (std::size_t i = 0; i < f.size(); ++i) {
    const std::complex<double> shift =
        std::exp(std::complex<double>(0.0, -2 * M_PI * f[i] * delay_s));
    h.push_back(std::abs(suu[i]) >= 0.01 * peak ? shift * spectrum(r.ryu, f[i]) / suu[i]
                                                : std::complex<double>(NAN, NAN));
  }
  return h;
}

void bode_block(HtmlReport& page, const IdentifyContext& ctx, const ident::IdentifyResult& r,
                double dt_s) {
  report::BodeCurve model{"model"};
  std::vector<double> f;
  bode_band_curve(r, model, f);
  if (f.empty()) {
    const double f_hi = 0.4 / dt_s;
    f = report::log_space(f_hi / 1000.0, f_hi, 160);
    for (double fh : f) model.response.push_back(r.model.response(fh));
  }
  report::BodeCurve measured{"from correlations",
                             correlation_frf(r, f, ctx.timing_correction_s.value_or(0.0))};
  measured.points = true;
  measured.color = "#555";
  const auto [mag, phase] = report::bode_charts("Bode plot", f, {model, measured});
  page.section("Frequency response");
  double db = 0.0, deg = 0.0;
  for (const auto& b : r.band) db = std::max(db, b.sd_db), deg = std::max(deg, b.sd_deg);
  page.paragraph(fmt::format(
      "Shaded: simultaneous 95 % band (factor {:.2f} standard deviations, holding at every "
      "frequency at once; at its widest +-{:.2g} dB and +-{:.2g} deg) from the asymptotic "
      "covariance of all the parameters with their correlations, the same covariance the "
      "online stop rule uses. Points: S_yu/S_uu from the correlations.{}",
      r.band_factor, r.band_factor * db, r.band_factor * deg,
      ctx.timing_correction_s ? " Phases and dead times refer to the plant (the sidecar's "
                                "sample timing)."
                              : ""));
  page.chart(mag).chart(phase);
}

void model_block(HtmlReport& page, const IdentifyContext& ctx, const ident::IdentifyResult& r) {
  page.section("Model");
  page.paragraph(fmt::format("H(s) = e^(-{:.4g} s) ({}) / ({})", r.model.delay_s,
                             polynomial_text(r.model.num), polynomial_text(r.model.den)));
  report::Table params{{"parameter", "value", "standard error"}};
  for (const auto& p : r.parameters) {
    params.rows.push_back(
        {p.name, fmt::format("{:.6g}", p.value), fmt::format("{:.3g}", p.std_error)});
  }
  page.table(params);
  if (r.derived.valid) {
    page.key_values(
        {{"static gain", fmt::format("{:.4g} +- {:.2g}", r.derived.gain, r.derived.gain_std)},
         {"natural frequency",
          fmt::format("{:.4g} +- {:.2g} Hz", r.derived.fn_hz, r.derived.fn_hz_std)},
         {"damping ratio", fmt::format("{:.4g} +- {:.2g}", r.derived.zeta, r.derived.zeta_std)},
         {"dead time", fmt::format("{:.4g} +- {:.2g} s", r.delay_s, r.delay_std_s)}});
  }
  page.paragraph("Settings: " + r.settings + "; standard errors: " + r.std_error_method +
                 "; input " + ctx.input + ", output " + ctx.output + ".");
}

}  // namespace

void write_identify_html(const std::filesystem::path& path, const IdentifyContext& ctx,
                         const ident::QualityReport& quality, const ident::IdentifyResult* r,
                         const signal::Correlation& ruu, const signal::Correlation& ryu) {
  const io::Recording& rec = *ctx.recording;
  HtmlReport page("rig identify: " + rec.source);
  page.key_values(
      {{"recording", rec.source},
       {"samples",
        fmt::format("{} at {:.6g} s ({})", rec.rows(), rec.dt_s, rec.sampling.dt_source)},
       {"rows", ctx.rows.reason},
       {"input / output", ctx.input + " / " + ctx.output},
       {"records", records_text(ctx)},
       {"asked", "methods " + ctx.method + ", order " + ctx.order_arg + ", delay " + ctx.delay_arg},
       {"dead time refers to",
        ctx.timing_correction_s
            ? fmt::format("the plant (y sampled {:.4g} s after u; {:+.4g} s added)",
                          rec.sidecar.y_sampled_after_s.value_or(0.0), *ctx.timing_correction_s)
            : std::string("the recording's rows (no sample timing in a sidecar)")},
       {"result",
        r ? fmt::format("validation fit {:.1f} % ({})", r->validation_fit_pct, r->structure.name())
        : ctx.no_model.empty() ? std::string("not identified: data-quality checks failed")
                               : "not identified: " + ctx.no_model}});
  for (const auto& w : rec.warnings) page.note(report::Tone::kWarning, w);
  quality_block(page, quality);
  if (r) {
    model_block(page, ctx, *r);
    fit_table_block(page, ctx, *r);
    validation_block(page, *r, rec.dt_s);
  }
  correlation_charts(page, ruu, ryu, r ? &r->model_ryu : nullptr);
  if (r) bode_block(page, ctx, *r, rec.dt_s);
  page.write(path);
}

std::string identify_summary(const IdentifyContext& ctx, const ident::QualityReport& quality,
                             const ident::IdentifyResult* r, const std::filesystem::path& out) {
  const io::Recording& rec = *ctx.recording;
  std::string s = fmt::format("rig identify: {} ({} samples, dt {:.6g} s, {} -> {})\n", rec.source,
                              rec.rows(), rec.dt_s, ctx.input, ctx.output);
  s += "  rows: " + ctx.rows.reason + "\n";
  for (const auto& w : rec.warnings) s += "  warning: " + w + "\n";
  for (const auto& f : quality.flags)
    s += fmt::format("  {}: {}\n", ident::to_string(f.severity), f.message);
  if (r) {
    s +=
        fmt::format("  model ({}): H(s) = e^(-{:.4g} s) ({}) / ({})\n", r->structure.name(),
                    r->model.delay_s, polynomial_text(r->model.num), polynomial_text(r->model.den));
    s += fmt::format("  chosen from {} structures: {}\n", r->table.rows.size(), r->table.rule);
    if (r->derived.valid) {
      s += fmt::format("  gain {:.4g} +- {:.2g}, fn {:.4g} +- {:.2g} Hz, zeta {:.4g} +- {:.2g}\n",
                       r->derived.gain, r->derived.gain_std, r->derived.fn_hz, r->derived.fn_hz_std,
                       r->derived.zeta, r->derived.zeta_std);
    }
    s += fmt::format(
        "  dead time {:.4g} +- {:.2g} s (refers to the {}), validation fit {:.1f} % "
        "on the {}\n",
        r->delay_s, r->delay_std_s, ctx.timing_correction_s ? "plant" : "rows",
        r->validation_fit_pct, r->validation.what);
    s += fmt::format("  wrote {}, {}, {}\n", (out / "model.json").string(),
                     (out / "report.json").string(), (out / "report.html").string());
  } else {
    if (!ctx.no_model.empty()) s += "  " + ctx.no_model + "\n";
    s += fmt::format("  not identified; wrote {}, {}\n", (out / "report.json").string(),
                     (out / "report.html").string());
  }
  return s;
}

}  // namespace rig::cli
