#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "rig/cli/identify_report.hpp"
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

// Band of |H| from seeded draws of the coefficients with their standard errors taken as
// independent (5 % and 95 % quantiles of 400 draws, seed 1).
std::pair<std::vector<double>, std::vector<double>> magnitude_band(const ident::IdentifyResult& r,
                                                                   const std::vector<double>& f) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> z(0.0, 1.0);
  const int draws = 400;
  std::vector<std::vector<double>> mags(f.size());
  for (int d = 0; d < draws; ++d) {
    model::TransferFunction tf = r.model;
    for (const auto& p : r.parameters) {
      if (!std::isfinite(p.std_error) || p.name.size() < 2) continue;
      const int power = std::atoi(p.name.c_str() + 1);
      Eigen::VectorXd& poly = p.name[0] == 'a' ? tf.den : tf.num;
      if (p.name[0] != 'a' && p.name[0] != 'b') continue;
      const Eigen::Index idx = poly.size() - 1 - power;
      if (idx >= 0 && idx < poly.size()) poly[idx] += p.std_error * z(rng);
    }
    for (std::size_t i = 0; i < f.size(); ++i) mags[i].push_back(std::abs(tf.response(f[i])));
  }
  std::vector<double> lo, hi;
  for (auto& m : mags) {
    std::sort(m.begin(), m.end());
    lo.push_back(m[std::size_t(0.05 * draws)]);
    hi.push_back(m[std::size_t(0.95 * draws)]);
  }
  return {lo, hi};
}

// Blackman-Tukey estimate H = S_yu / S_uu from the correlations (Bartlett lag window),
// where the input carries at least 1 % of its peak power; NaN elsewhere.
std::vector<std::complex<double>> correlation_frf(const ident::IdentifyResult& r,
                                                  const std::vector<double>& f) {
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
    h.push_back(std::abs(suu[i]) >= 0.01 * peak ? spectrum(r.ryu, f[i]) / suu[i]
                                                : std::complex<double>(NAN, NAN));
  }
  return h;
}

void bode_block(HtmlReport& page, const ident::IdentifyResult& r, double dt_s) {
  const double f_hi = 0.4 / dt_s;
  const auto f = report::log_space(f_hi / 1000.0, f_hi, 160);
  report::BodeCurve model{"model"};
  for (double fh : f) model.response.push_back(r.model.response(fh));
  auto [lo, hi] = magnitude_band(r, f);
  model.mag_lo = lo;
  model.mag_hi = hi;
  report::BodeCurve measured{"from correlations", correlation_frf(r, f)};
  measured.points = true;
  measured.color = "#555";
  const auto [mag, phase] = report::bode_charts("Bode plot", f, {model, measured});
  page.section("Frequency response");
  page.paragraph(
      "Shaded: 5-95 % band of |H| from the parameter standard errors (taken as "
      "independent, 400 seeded draws). Points: S_yu/S_uu from the correlations.");
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
  report::Table orders{{"order n/m", "fit %", "validation fit %", "score", "delay (s)"}};
  for (std::size_t i = 0; i < r.order_table.size(); ++i) {
    const auto& o = r.order_table[i];
    orders.rows.push_back({fmt::format("{}/{}", o.order.n, o.order.m),
                           fmt::format("{:.1f}", o.fit_pct),
                           fmt::format("{:.1f}", o.validation_fit_pct),
                           fmt::format("{:.2f}", o.score), fmt::format("{:.4g}", o.delay_s)});
    if (o.order == r.order) orders.highlight_rows.push_back(i);
  }
  page.section("Model orders (estimated on the first part, validated on the rest)");
  page.table(orders);
  page.paragraph("Settings: " + r.settings + "; standard errors: " + r.std_error_method +
                 "; input " + ctx.input + ", output " + ctx.output + ".");
}

}  // namespace

void write_identify_html(const std::filesystem::path& path, const IdentifyContext& ctx,
                         const ident::QualityReport& quality, const ident::IdentifyResult* r,
                         const signal::Correlation& ruu, const signal::Correlation& ryu) {
  const io::Recording& rec = *ctx.recording;
  HtmlReport page("rig identify: " + rec.source);
  page.key_values({{"recording", rec.source},
                   {"samples", fmt::format("{} at {:.6g} s ({})", rec.rows(), rec.dt_s,
                                           rec.sampling.dt_source)},
                   {"rows", ctx.rows.reason},
                   {"input / output", ctx.input + " / " + ctx.output},
                   {"method", ctx.method + ", order " + ctx.order_arg + ", delay " + ctx.delay_arg},
                   {"result", r ? fmt::format("validation fit {:.1f} % (order {}/{})",
                                              r->validation_fit_pct, r->order.n, r->order.m)
                                : std::string("not identified: data-quality checks failed")}});
  for (const auto& w : rec.warnings) page.note(report::Tone::kWarning, w);
  quality_block(page, quality);
  if (r) model_block(page, ctx, *r);
  correlation_charts(page, ruu, ryu, r ? &r->model_ryu : nullptr);
  if (r) bode_block(page, *r, rec.dt_s);
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
    s += fmt::format("  model ({}, order {}/{}): H(s) = e^(-{:.4g} s) ({}) / ({})\n", ctx.method,
                     r->order.n, r->order.m, r->model.delay_s, polynomial_text(r->model.num),
                     polynomial_text(r->model.den));
    if (r->derived.valid) {
      s += fmt::format("  gain {:.4g} +- {:.2g}, fn {:.4g} +- {:.2g} Hz, zeta {:.4g} +- {:.2g}\n",
                       r->derived.gain, r->derived.gain_std, r->derived.fn_hz, r->derived.fn_hz_std,
                       r->derived.zeta, r->derived.zeta_std);
    }
    s += fmt::format("  dead time {:.4g} +- {:.2g} s, validation fit {:.1f} %\n", r->delay_s,
                     r->delay_std_s, r->validation_fit_pct);
    s += fmt::format("  wrote {}, {}, {}\n", (out / "model.json").string(),
                     (out / "report.json").string(), (out / "report.html").string());
  } else {
    s += fmt::format("  not identified; wrote {}, {}\n", (out / "report.json").string(),
                     (out / "report.html").string());
  }
  return s;
}

}  // namespace rig::cli
