// report.html of `rig diagnose`: verdict and explanation first, then the plots a person
// would look at to check it.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/diagnose/effect_registry.hpp"
#include "rig/diagnose/report_out.hpp"
#include "rig/fra/h1.hpp"
#include "rig/report/bode_chart.hpp"
#include "rig/report/html_report.hpp"

namespace rig::diagnose {
namespace {

using report::Chart;
using report::Series;

std::vector<double> seg(const Eigen::VectorXd& x, Eigen::Index from, Eigen::Index n) {
  return {x.data() + from, x.data() + from + n};
}

Chart time_chart(const DiagnoseResult& r) {
  const Problem& pr = r.problem;
  const Eigen::Index n = pr.u.size(), len = std::min<Eigen::Index>(n, std::llround(40.0 / pr.dt_s));
  Eigen::Index from = std::max(pr.active_from, r.warmup);
  while (from < n - len && pr.val_weight(from) <= 0.0) ++from;
  from = std::min(from, n - len);
  Chart c{"Recorded vs simulated (a validation stretch)",
          "time (s)",
          "output (mean removed)",
          {},
          {},
          {},
          false,
          false,
          320};
  for (Eigen::Index k = 0; k < len; ++k) c.x.push_back(static_cast<double>(from + k) * pr.dt_s);
  c.series.push_back({"recorded", seg(pr.y, from, len), "#444", false, false, 1.0});
  c.series.push_back({"model", seg(r.baseline_yhat, from, len), "#d62728", false, false, 1.5});
  if (const HypothesisFit* h = r.chosen(); h && h->yhat.size() == n)
    c.series.push_back(
        {"augmented (" + h->name() + ")", seg(h->yhat, from, len), "#2ca02c", false, false, 1.5});
  return c;
}

std::pair<Chart, Chart> spectrum_charts(const DiagnoseResult& r) {
  const Problem& pr = r.problem;
  fra::WelchOptions wo;
  wo.segment_length = welch_segment(pr.u.size());
  const auto before = fra::welch_cross_spectra(pr.u, pr.y - r.baseline_yhat, pr.dt_s, wo);
  const HypothesisFit* h = r.chosen();
  const bool after = h && h->yhat.size() == pr.y.size();
  const auto sa = after ? fra::welch_cross_spectra(pr.u, pr.y - h->yhat, pr.dt_s, wo) : before;
  Chart psd{"Residual spectrum (located band highlighted)",
            "frequency (Hz)",
            "PSD (arbitrary scale)",
            {},
            {},
            {},
            true,
            true,
            320};
  Chart coh{"Residual coherence with the input",
            "frequency (Hz)",
            "coherence",
            {},
            {},
            {},
            true,
            false,
            260};
  Series b{"residual, model", {}, "#d62728"}, a{"residual, augmented", {}, "#2ca02c"},
      band{"located band", {}, "#ff7f0e", false, true, 2.0};
  Series rc{"residual coherence", {}, "#1f77b4"}, th{"null threshold", {}, "#888", true};
  const auto& bins = r.location.freq.bins;
  for (Eigen::Index k = 1; k < before.freq_hz.size(); ++k) {
    psd.x.push_back(before.freq_hz(k));
    b.y.push_back(before.gyy(k));
    a.y.push_back(sa.gyy(k));
    const bool in = static_cast<std::size_t>(k - 1) < bins.size() &&
                    bins[static_cast<std::size_t>(k - 1)].significant;
    band.y.push_back(in ? before.gyy(k) : NAN);
    coh.x.push_back(before.freq_hz(k));
    rc.y.push_back(static_cast<std::size_t>(k - 1) < bins.size()
                       ? bins[static_cast<std::size_t>(k - 1)].residual_coherence
                       : NAN);
    th.y.push_back(r.location.freq.coherence_threshold);
  }
  psd.series = {b, band};
  if (after) psd.series.push_back(a);
  coh.series = {rc, th};
  return {psd, coh};
}

Chart amplitude_chart(const DiagnoseResult& r) {
  Chart c{"Gain each input level sees (recording / model)",
          "input level (rms of |u| in the band)",
          "relative gain",
          {},
          {},
          {},
          false,
          false,
          260};
  Series g{"local gain", {}, "#1f77b4", false, true, 2.0}, hi{"+1 std", {}, "#9ecae1", true},
      lo{"-1 std", {}, "#9ecae1", true};
  for (const auto& b : r.location.amp.by_level) {
    c.x.push_back(b.level);
    g.y.push_back(b.gain), hi.y.push_back(b.gain + b.gain_std), lo.y.push_back(b.gain - b.gain_std);
  }
  c.series = {g, hi, lo};
  c.bands.push_back({1, 2, "rgba(31,119,180,0.18)"});
  return c;
}

Chart cross_chart(const DiagnoseResult& r) {
  const auto& t = r.location.tests;
  Chart c{"Residual-input cross-correlation (resid)",
          "lag (s)",
          "correlation",
          {},
          {},
          {},
          false,
          false,
          260};
  Series x{"r_ru", {}, "#1f77b4"}, up{"99 % bound", {}, "#888", true},
      dn{"-99 % bound", {}, "#888", true};
  for (Eigen::Index k = 0; k < t.cross_corr.size(); ++k) {
    c.x.push_back(t.lags_s(k));
    x.y.push_back(t.cross_corr(k)), up.y.push_back(t.cross_bound(k)),
        dn.y.push_back(-t.cross_bound(k));
  }
  c.series = {x, up, dn};
  return c;
}

void bode_section(report::HtmlReport& page, const DiagnoseResult& r) {
  std::vector<double> f;
  std::vector<std::complex<double>> meas, model, aug;
  const HypothesisFit* h = r.chosen();
  for (const auto& b : r.location.freq.bins) {
    if (b.freq_hz > r.location.freq.input_band_hz * 1.5 || b.coherence < 0.3) continue;
    f.push_back(b.freq_hz);
    meas.push_back(b.measured);
    model.push_back(b.model);
    aug.push_back(h ? h->tf.response(b.freq_hz) : b.model);
  }
  if (f.size() < 2) return;
  std::vector<report::BodeCurve> curves = {{"measured H1", meas, {}, {}, true, "#444"},
                                           {"model", model, {}, {}, false, "#d62728"}};
  if (h) curves.push_back({"augmented (linear part)", aug, {}, {}, false, "#2ca02c"});
  auto [mag, phase] = report::bode_charts("Recording's FRF vs model", f, curves);
  page.section("Frequency response").chart(mag).chart(phase);
}

// "rate_limit (in the loop)+drift": the effects with the places of those not at the input.
std::string placed_name(const HypothesisFit& h) {
  std::string s;
  for (const auto& e : h.effects) {
    if (!s.empty()) s.push_back('+');
    s += to_string(e.effect);
    s += place_suffix(e.place);
  }
  return s;
}

report::Table hypotheses_table(const DiagnoseResult& r) {
  report::Table t{{"rank", "effect", "parameters", "fit before (%)", "fit after (%)",
                   "validation before (%)", "validation after (%)", "score"},
                  {},
                  {}};
  for (std::size_t i = 0; i < r.hypotheses.size(); ++i) {
    const auto& h = r.hypotheses[i];
    std::string params;
    for (const auto& e : h.effects) {
      const auto specs = parameter_specs(e.effect, r.problem.scales);
      for (std::size_t j = 0; j < acting_params(e); ++j)
        params +=
            fmt::format("{}{}={:.4g}", params.empty() ? "" : ", ", specs[j].name, e.params[j]);
      const auto place = place_specs(e.place, r.problem.scales);
      for (std::size_t j = 0; j < e.place_params.size(); ++j)
        params += fmt::format(", {}={:.4g}", place[j].name, e.place_params[j]);
    }
    t.rows.push_back(
        {std::to_string(i + 1), placed_name(h), params, fmt::format("{:.1f}", h.fit_before),
         fmt::format("{:.1f}", h.fit_after), fmt::format("{:.1f}", h.validation_fit_before),
         fmt::format("{:.1f}", h.validation_fit_after), fmt::format("{:+.2f}", h.score)});
  }
  if (r.chosen_index >= 0) t.highlight_rows.push_back(static_cast<std::size_t>(r.chosen_index));
  return t;
}

}  // namespace

void write_report_html(const DiagnoseResult& r, const ReportContext& c,
                       const std::filesystem::path& file,
                       const std::function<void(report::HtmlReport&)>& more) {
  report::HtmlReport page("rig diagnose: " + c.recording + " vs " + c.model);
  const report::Tone tone = r.verdict == "none"          ? report::Tone::kOk
                            : r.verdict == "unexplained" ? report::Tone::kWarning
                                                         : report::Tone::kInfo;
  std::string where;  // the place of the verdict's effect, when not on the input
  if (const HypothesisFit* h = r.chosen())
    for (const auto& e : h->effects)
      if (to_string(e.effect) == r.verdict) where = place_suffix(e.place);
  page.note(tone, "Verdict: " + r.verdict + where);
  page.paragraph(r.explanation);
  const auto& loc = r.location;
  std::string grid = "not recorded";  // the bus frequency's share (bus_frequency.hpp)
  if (r.bus_frequency)
    grid = r.bus_frequency->used
               ? fmt::format("{:.3g} rms taken out ({:.0f} % of the residual)",
                             r.bus_frequency->share_rms, 100.0 * r.bus_frequency->residual_share)
           : !(r.bus_frequency->frequency_rms_hz > 0.0) ? "constant"
           : r.bus_frequency->bias_coherence > thresholds::kBusFrequencyMaxBiasCoherence
               ? "not the grid's (follows the bias)"
               : "not used (clipped output)";
  page.key_values(
      {{"grid's share (bus frequency)", grid},
       {"fit before (whole record after warm-up)", fmt::format("{:.1f} %", r.fit_before_pct)},
       {"validation fit before", fmt::format("{:.1f} %", r.validation_fit_before_pct)},
       {"band", loc.freq.band_hz ? fmt::format("{:.3g} - {:.3g} Hz", loc.freq.band_hz->first,
                                               loc.freq.band_hz->second)
                                 : "none"},
       {"time windows", std::to_string(loc.windows.size())},
       {"amplitude dependent", loc.amp.fails() ? "yes" : "no"},
       {"residual independent of input", loc.tests.independent ? "yes" : "no"},
       {"split", fmt::format("{} interleaved blocks after {:.1f} s warm-up", r.blocks,
                             static_cast<double>(r.warmup) * r.problem.dt_s)},
       {"run time", fmt::format("{:.2f} s", r.elapsed_s)}});
  if (more) more(page);  // what the verdict changed (the plant), before the evidence
  page.section("Time").chart(time_chart(r));
  auto [psd, coh] = spectrum_charts(r);
  page.section("Where in frequency").chart(psd).chart(coh);
  bode_section(page, r);
  page.section("Amplitude dependence").chart(amplitude_chart(r));
  page.section("Residual tests").chart(cross_chart(r));
  page.section("Hypotheses (ranked)").table(hypotheses_table(r));
  page.write(file);
}

}  // namespace rig::diagnose
