// The sections of `rig identify`'s report.html that show the fit table, the validation
// (measured against model output, residual tests) and the Bode plot with its band.
#include "rig/cli/identify_report_sections.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>

#include "rig/report/bode_chart.hpp"
#include "rig/report/json_out.hpp"

namespace rig::cli {
namespace {

using report::Chart;
using report::Series;

// Time plots keep at most this many points (every k-th sample): enough to see the fit.
constexpr Eigen::Index kMaxTimePoints = 6000;
// The close-up of the validation: its first seconds, where each swing can be followed.
constexpr double kCloseUpS = 20.0;
// Adequate structures listed on the page (all of them are in report.json).
constexpr std::size_t kMaxAdequateRows = 12;

std::string fit_cell(const ident::StructureFit& f, bool chosen) {
  if (!f.ok) return "-";
  return fmt::format("{:.1f}{}{}", f.validation_fit_pct, f.adequate ? " \u2713" : "",
                     chosen ? " *" : "");
}

// Seed 001's Table 1: validation fit by order (rows) and estimator/delay (columns).
void pivot_table(report::HtmlReport& page, const ident::StructureTable& t) {
  std::vector<std::string> columns;
  std::map<std::string, std::map<std::string, std::string>> cells;
  std::vector<std::string> orders;
  std::string chosen_order;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const ident::StructureFit& f = t.rows[i];
    const std::string col = std::string(ident::to_string(f.structure.method)) +
                            (f.structure.delay_estimated ? " +Td" : "");
    const std::string row = fmt::format("{}/{}", f.structure.order.n, f.structure.order.m);
    if (std::find(columns.begin(), columns.end(), col) == columns.end()) columns.push_back(col);
    if (std::find(orders.begin(), orders.end(), row) == orders.end()) orders.push_back(row);
    cells[row][col] = fit_cell(f, static_cast<int>(i) == t.chosen);
    if (static_cast<int>(i) == t.chosen) chosen_order = row;
  }
  report::Table table{{"order n/m"}};
  for (const auto& c : columns) table.header.push_back(c);
  for (std::size_t r = 0; r < orders.size(); ++r) {
    std::vector<std::string> row{orders[r]};
    for (const auto& c : columns)
      row.push_back(cells[orders[r]].count(c) ? cells[orders[r]][c] : "");
    table.rows.push_back(row);
    if (orders[r] == chosen_order) table.highlight_rows.push_back(r);
  }
  page.table(table);
}

void adequate_table(report::HtmlReport& page, const ident::StructureTable& t) {
  double aic0 = INFINITY, bic0 = INFINITY;
  const ident::StructureFit *by_aic = nullptr, *by_bic = nullptr;
  for (const auto& f : t.rows) {
    if (!f.ok) continue;
    if (f.aic < aic0) aic0 = f.aic, by_aic = &f;
    if (f.bic < bic0) bic0 = f.bic, by_bic = &f;
  }
  report::Table table{{"structure", "parameters", "estimation fit %", "validation fit %",
                       "delta AIC", "delta BIC", "dead time (s)"}};
  // The simplest first (the order the rule reads them in).
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if (t.rows[i].adequate) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return t.rows[a].structure.parameters() < t.rows[b].structure.parameters();
  });
  const std::size_t total = order.size();
  if (order.size() > kMaxAdequateRows) order.resize(kMaxAdequateRows);
  for (std::size_t i : order) {
    const ident::StructureFit& f = t.rows[i];
    if (static_cast<int>(i) == t.chosen) table.highlight_rows.push_back(table.rows.size());
    table.rows.push_back({f.structure.name(), std::to_string(f.structure.parameters()),
                          fmt::format("{:.1f}", f.estimation_fit_pct),
                          fmt::format("{:.2f}", f.validation_fit_pct),
                          fmt::format("{:.0f}", f.aic - aic0), fmt::format("{:.0f}", f.bic - bic0),
                          fmt::format("{:.4g}", f.model.delay_s)});
  }
  page.paragraph(
      fmt::format("Adequate structures, simplest first (the chosen one highlighted){}:",
                  total > order.size()
                      ? fmt::format("; {} of {}, every one is in report.json", order.size(), total)
                      : std::string()));
  page.table(table);
  if (by_aic && by_bic) {
    page.paragraph(fmt::format(
        "Lowest AIC: {} (validation fit {:.1f} %); lowest BIC: {} ({:.1f} %). AIC and BIC "
        "judge the estimation records only; with many samples of coloured noise they keep "
        "rewarding parameters, so the choice is made on the validation record.",
        by_aic->structure.name(), by_aic->validation_fit_pct, by_bic->structure.name(),
        by_bic->validation_fit_pct));
  }
}

Series thinned(const std::string& label, const Eigen::VectorXd& v, Eigen::Index step,
               const std::string& color) {
  Series s{label, {}, color};
  for (Eigen::Index i = 0; i < v.size(); i += step) s.y.push_back(v(i));
  return s;
}

void bounded_chart(report::HtmlReport& page, const std::string& title, const std::string& y,
                   const std::vector<double>& lags, std::vector<double> values,
                   std::vector<double> bound) {
  Chart c{title, "lag (s)", y, lags};
  c.series.push_back({y, std::move(values), "#1f77b4"});
  std::vector<double> lower(bound.size());
  for (std::size_t i = 0; i < bound.size(); ++i) lower[i] = -bound[i];
  c.series.push_back({"99 % bound", std::move(bound), "#d62728", true});
  c.series.push_back({"-99 % bound", std::move(lower), "#d62728", true});
  c.height_px = 240;
  page.chart(c);
}

}  // namespace

void fit_table_block(report::HtmlReport& page, const IdentifyContext& ctx,
                     const ident::IdentifyResult& r) {
  page.section(ctx.separate_validation()
                   ? "Fit table: estimated on the estimation records, validation fit % on the "
                     "validation record"
                   : "Fit table: estimated on the first part, validation fit % on the rest");
  page.paragraph("Chosen (*, highlighted): " + r.structure.name() +
                 ", by the rule: " + r.table.rule + ". +Td: dead time estimated; otherwise " +
                 (ctx.delay_arg == "auto" ? std::string("none") : ctx.delay_arg + " s") + ".");
  pivot_table(page, r.table);
  adequate_table(page, r.table);
}

void validation_block(report::HtmlReport& page, const ident::IdentifyResult& r, double dt_s) {
  const ident::ValidationData& v = r.validation;
  if (v.y.size() == 0) return;
  page.section("Validation: measured and model output (" + v.what + ")");
  const Eigen::Index step = std::max<Eigen::Index>(1, v.y.size() / kMaxTimePoints);
  std::vector<double> t;
  for (Eigen::Index i = 0; i < v.y.size(); i += step) t.push_back(static_cast<double>(i) * dt_s);
  Chart c{fmt::format("Measured and model output, fit {:.1f} %", v.fit_pct), "time (s)",
          "output (mean removed)", t};
  c.series.push_back(thinned("measured", v.y, step, "#555"));
  c.series.push_back(thinned("model", v.y_model, step, "#d62728"));
  c.series.push_back(thinned("residual", v.y - v.y_model, step, "#2ca02c"));
  page.chart(c);
  const Eigen::Index close = std::min<Eigen::Index>(v.y.size(), std::lround(kCloseUpS / dt_s));
  std::vector<double> tc;
  for (Eigen::Index i = 0; i < close; ++i) tc.push_back(static_cast<double>(i) * dt_s);
  Chart zoom{fmt::format("The first {:.0f} s", kCloseUpS), "time (s)", "output (mean removed)", tc};
  zoom.series.push_back(thinned("measured", v.y.head(close), 1, "#555"));
  zoom.series.push_back(thinned("model", v.y_model.head(close), 1, "#d62728"));
  page.chart(zoom);
  const ident::ResidualTests& rt = v.residuals;
  const Eigen::Index m = rt.auto_corr.size() - 1;
  std::vector<double> lags_auto, lags_cross, cross_bound;
  for (Eigen::Index k = 0; k <= m; ++k) lags_auto.push_back(rt.lags_s(m + k));
  for (Eigen::Index k = 0; k < rt.lags_s.size(); ++k) lags_cross.push_back(rt.lags_s(k));
  for (Eigen::Index k = 0; k < rt.cross_bound.size(); ++k) cross_bound.push_back(rt.cross_bound(k));
  page.paragraph(fmt::format(
      "Residual tests (as MATLAB resid, 99 % bounds): the residual is {} (largest "
      "auto-correlation {:.1f} x its bound) and {} of past inputs (largest cross-correlation "
      "{:.1f} x its bound at {:.3g} s, family-wise limit {:.2f} x). An output-error model is "
      "judged by the second: a residual correlated with the input is unmodelled dynamics; a "
      "coloured residual that is not is a disturbance the model does not describe.",
      rt.white ? "white" : "coloured", rt.whiteness_ratio,
      rt.independent ? "independent" : "not independent", rt.cross_ratio, rt.cross_peak_lag_s,
      rt.cross_threshold));
  bounded_chart(page, "Residual auto-correlation", "rho_ee", lags_auto,
                report::to_std_vector(rt.auto_corr),
                std::vector<double>(lags_auto.size(), rt.auto_bound));
  bounded_chart(page, "Input-residual cross-correlation (input leads at positive lags)", "rho_eu",
                lags_cross, report::to_std_vector(rt.cross_corr), cross_bound);
}

void bode_band_curve(const ident::IdentifyResult& r, report::BodeCurve& model,
                     std::vector<double>& freqs_hz) {
  freqs_hz.clear();
  std::vector<double> lo, hi, phase;
  const double c = r.band_factor;
  for (const ident::FrfUncertainty& b : r.band) {
    freqs_hz.push_back(b.freq_hz);
    model.response.push_back(r.model.response(b.freq_hz));
    const double mag = std::abs(model.response.back());
    lo.push_back(mag * std::pow(10.0, -c * b.sd_db / 20.0));
    hi.push_back(mag * std::pow(10.0, c * b.sd_db / 20.0));
    phase.push_back(c * b.sd_deg);
  }
  if (std::isfinite(c) && c > 0.0) {
    model.mag_lo = lo;
    model.mag_hi = hi;
    model.phase_halfwidth_deg = phase;
  }
}

}  // namespace rig::cli
