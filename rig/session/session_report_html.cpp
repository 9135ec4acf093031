// report.html of a commissioning test: summary, Bode overlay (MMFM model, swept sine, H1)
// with coherence, correlation functions, parameter convergence with uncertainty, and the
// power deviation against the band.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <set>

#include "rig/report/bode_chart.hpp"
#include "rig/report/html_report.hpp"
#include "rig/session/session_outputs.hpp"

namespace rig::session {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

report::Tone tone_for(int exit_code) {
  if (exit_code == kExitOk) return report::Tone::kOk;
  if (exit_code == kExitAcceptance) return report::Tone::kWarning;
  return report::Tone::kFatal;
}

std::string loop_timing_text(const LoopTimingSummary& t) {
  const std::string exchange = fmt::format("exchange p50 {:.2f} ms, p99 {:.2f} ms, max {:.2f} ms",
                                           t.exchange_p50_ms, t.exchange_p99_ms, t.exchange_max_ms);
  if (t.mode != "realtime") {
    return fmt::format("lockstep, {} exchanges of {:.1f} ms plant time; {}", t.cycles, t.period_ms,
                       exchange);
  }
  return fmt::format(
      "realtime at {:.0f} Hz: cycle start late by p50 {:.3f} ms, p99 {:.3f} ms, "
      "max {:.2f} ms; {} overruns in {} cycles, schedule moved {} time{} by {:.0f} ms "
      "in all ({}{}); {}",
      1e3 / t.period_ms, t.jitter_p50_ms, t.jitter_p99_ms, t.jitter_max_ms, t.overruns, t.cycles,
      t.slips, t.slips == 1 ? "" : "s", t.slip_total_ms,
      t.realtime_priority ? "SCHED_FIFO" : "normal priority",
      t.cpu_latency_held ? ", CPUs kept out of deep idle" : "", exchange);
}

void summary(report::HtmlReport& page, const SessionData& d) {
  page.note(tone_for(d.exit_code), fmt::format("exit code {}: {}", d.exit_code, d.outcome));
  std::vector<std::pair<std::string, std::string>> kv = {
      {"link", d.link_uri},
      {"plant preset", d.preset.empty() ? "-" : d.preset},
      {"test time", fmt::format("{:.1f} s (wall {:.1f} s)", d.test_time_s, d.wall_time_s)},
      {"power band", fmt::format("+-{:.2f} % of P0{}", d.config.safety.band_pct,
                                 d.config.safety.band_pct > kStandardBandPct
                                     ? " (ABOVE 3 %: explicit override in the test file)"
                                     : "")},
      {"largest deviation", fmt::format("{:.2f} % of P0", d.max_abs_deviation_pct)}};
  if (d.steady) {
    kv.push_back(
        {"steady state", fmt::format("P0 {:.1f} kW, noise {:.3f} %, drift {:.3f} %",
                                     d.steady->p0_kw, d.steady->noise_pct, d.steady->drift_pct)});
  }
  if (d.pilot && d.pilot->ok) {
    kv.push_back({"pilot", fmt::format("gain {:.1f} kW/%, excitation std {:.3f} %",
                                       d.pilot->gain_kw_per_pct, d.pilot->planned_std_pct)});
  }
  if (d.activation) {
    kv.push_back(
        {"bias acknowledged", d.activation->acknowledged
                                  ? fmt::format("yes, after {:.2f} s (status 0x{:04x})",
                                                d.activation->waited_s, d.activation->status)
                                  : fmt::format("NO within {:.2f} s (status 0x{:04x})",
                                                d.activation->waited_s, d.activation->status)});
  }
  if (d.excitation.duration_s > 0.0) {
    const ExcitationResult& x = d.excitation;
    kv.push_back(
        {"excitation",
         fmt::format("{:.0f} s, applied std {:.4f} % of {:.4f} % planned ({:.0f} %), {}",
                     x.duration_s, x.applied_std_pct, x.planned_std_pct,
                     x.planned_std_pct > 0 ? 100.0 * x.applied_std_pct / x.planned_std_pct : 0.0,
                     x.stop_reason)});
  }
  if (!d.model_rejected.empty()) kv.push_back({"no model", d.model_rejected});
  if (d.excitation.mmfm && d.excitation.mmfm->derived.valid) {
    const auto& g = d.excitation.mmfm->derived;
    kv.push_back({"MMFM model", fmt::format("K {:.2f}+-{:.2f} kW/%, fn {:.3f}+-{:.3f} Hz, "
                                            "zeta {:.3f}+-{:.3f}, Td {:.1f}+-{:.1f} ms",
                                            g.gain, g.gain_std, g.fn_hz, g.fn_hz_std, g.zeta,
                                            g.zeta_std, 1e3 * d.excitation.mmfm->delay_s,
                                            1e3 * d.excitation.mmfm->delay_std_s)});
  }
  if (d.compare_sweep) kv.push_back({"MMFM vs swept sine", d.compare_sweep->summary});
  if (d.compare_h1) kv.push_back({"MMFM vs H1", d.compare_h1->summary});
  if (d.loop_timing && d.loop_timing->cycles > 0) {
    kv.push_back({"loop timing", loop_timing_text(*d.loop_timing)});
  }
  if (d.trip) kv.push_back({"trip", fmt::format("{}: {}", to_string(d.trip->cause), d.trip->text)});
  if (d.ramp_down.attempted) {
    kv.push_back({"ramp-down", d.ramp_down.cleared
                                   ? fmt::format("bias at baseline, enable cleared{}",
                                                 d.ramp_down.reconnects > 0
                                                     ? fmt::format(" (after {} reconnection(s))",
                                                                   d.ramp_down.reconnects)
                                                     : std::string())
                                   : "NOT confirmed: " + d.ramp_down.error +
                                         " (the governor's heartbeat rule removes the bias)"});
  }
  page.section("Summary").key_values(kv);
}

// Phase of each curve: the first (continuous) curve unwrapped along frequency, the others
// (sparse measured points) moved by whole turns to the branch nearest to it.
std::vector<report::Series> phase_series(const std::vector<double>& f,
                                         const std::vector<report::BodeCurve>& curves) {
  std::vector<report::Series> out;
  std::vector<double> reference;
  for (const auto& c : curves) {
    report::Series s{c.label, {}, c.color, false, c.points, c.points ? 0.0 : 1.5};
    double previous = kNaN;
    for (std::size_t i = 0; i < f.size(); ++i) {
      double p = std::arg(c.response[i]) * 180.0 / M_PI;
      const double near = reference.empty() ? previous : reference[i];
      if (std::isfinite(p) && std::isfinite(near)) p += 360.0 * std::round((near - p) / 360.0);
      if (std::isfinite(p)) previous = p;
      s.y.push_back(p);
    }
    if (reference.empty()) reference = s.y;
    out.push_back(s);
  }
  return out;
}

void bode(report::HtmlReport& page, const SessionData& d) {
  if (!d.excitation.mmfm && d.sweep.empty() && d.excitation.h1.empty()) return;
  const double f_lo = std::min(0.1, d.config.sweep.from_hz);
  const double f_hi = std::max(10.0, d.config.sweep.to_hz);
  std::set<double> grid;
  for (double f : report::log_space(f_lo, f_hi, 160)) grid.insert(f);
  for (const auto& p : d.sweep) grid.insert(p.freq_hz);
  for (const auto& p : d.excitation.h1)
    if (p.freq_hz >= f_lo && p.freq_hz <= f_hi) grid.insert(p.freq_hz);
  const std::vector<double> f(grid.begin(), grid.end());
  auto measured = [&](const std::vector<model::FrfPoint>& pts) {
    std::vector<std::complex<double>> h(f.size(), {kNaN, kNaN});
    for (const auto& p : pts) {
      const auto it = std::lower_bound(f.begin(), f.end(), p.freq_hz);
      if (it != f.end() && *it == p.freq_hz)
        h[static_cast<std::size_t>(it - f.begin())] = p.value();
    }
    return h;
  };
  std::vector<report::BodeCurve> curves;
  if (d.excitation.mmfm) {
    report::BodeCurve m{"MMFM model", {}, {}, {}, false, ""};
    for (double x : f) m.response.push_back(d.excitation.mmfm->model.response(x));
    curves.push_back(m);
  }
  if (!d.sweep.empty())
    curves.push_back({"swept sine", measured(d.sweep), {}, {}, true, "#d62728"});
  if (!d.excitation.h1.empty())
    curves.push_back({"H1 (noise-driven)", measured(d.excitation.h1), {}, {}, true, "#2ca02c"});
  auto [mag, phase] = report::bode_charts("Frequency response, kW per % bias", f, curves);
  phase.series = phase_series(f, curves);
  page.section("Frequency response").chart(mag).chart(phase);
  report::Chart coh{"Coherence", "frequency (Hz)", "coherence", f, {}, {}, true, false, 220};
  auto coherence = [&](const std::vector<model::FrfPoint>& pts, const std::string& label,
                       const std::string& color) {
    report::Series s{label, std::vector<double>(f.size(), kNaN), color, false, true, 1.5};
    for (const auto& p : pts) {
      const auto it = std::lower_bound(f.begin(), f.end(), p.freq_hz);
      if (it != f.end() && *it == p.freq_hz)
        s.y[static_cast<std::size_t>(it - f.begin())] = p.coherence;
    }
    coh.series.push_back(s);
  };
  if (!d.sweep.empty()) coherence(d.sweep, "swept sine", "#d62728");
  if (!d.excitation.h1.empty()) coherence(d.excitation.h1, "H1", "#2ca02c");
  if (!coh.series.empty()) page.chart(coh);
}

void correlations(report::HtmlReport& page, const SessionData& d) {
  if (d.excitation.ryu.size() == 0 || d.excitation.ruu.size() != d.excitation.ryu.size()) return;
  report::Chart c{
      "Correlation functions (AC-coupled, averaged)", "lag (s)", "", {}, {}, {}, false, false, 280};
  report::Series ruu{"r_uu (%^2)", {}, "", false, false, 1.5};
  report::Series ryu{"r_yu (kW %)", {}, "", false, false, 1.5};
  report::Series model{"model h * r_uu", {}, "", true, false, 1.5};
  const bool has_model =
      d.excitation.mmfm && d.excitation.mmfm->model_ryu.size() == d.excitation.ryu.size();
  for (Eigen::Index i = 0; i < d.excitation.ryu.size(); ++i) {
    c.x.push_back(d.excitation.ryu.lag_s(i));
    ruu.y.push_back(d.excitation.ruu.r(i));
    ryu.y.push_back(d.excitation.ryu.r(i));
    if (has_model) model.y.push_back(d.excitation.mmfm->model_ryu.r(i));
  }
  report::Chart a = c;
  a.title = "Auto-correlation of the applied excitation";
  a.series = {ruu};
  c.title = "Cross-correlation power/excitation";
  c.series = {ryu};
  if (has_model) c.series.push_back(model);
  page.section("Correlation functions").chart(a).chart(c);
}

void convergence(report::HtmlReport& page, const SessionData& d) {
  std::vector<const BlockEstimate*> ok;
  // From the third block on: the standard errors need three blocks of spread.
  for (const auto& e : d.excitation.history) {
    if (e.ok && e.derived.valid && e.block >= 3) ok.push_back(&e);
  }
  if (ok.empty()) return;
  page.section("Parameter convergence (estimate +- 1 standard error)");
  auto chart = [&](const std::string& name, auto value, auto se) {
    report::Chart c{name, "excitation time (s)", name, {}, {}, {}, false, false, 220};
    report::Series v{name, {}, "", false, true, 1.5};
    report::Series hi{"+1 se", {}, "#9ab", true, false, 1.0};
    report::Series lo{"-1 se", {}, "#9ab", true, false, 1.0};
    for (const auto* e : ok) {
      c.x.push_back(e->t_s);
      v.y.push_back(value(*e));
      const double s = std::isfinite(se(*e)) ? se(*e) : 0.0;
      hi.y.push_back(value(*e) + s);
      lo.y.push_back(value(*e) - s);
    }
    c.series = {v, hi, lo};
    c.bands.push_back({1, 2, "rgba(31,119,180,0.18)"});
    page.chart(c);
  };
  chart(
      "gain K (kW/%)", [](const BlockEstimate& e) { return e.derived.gain; },
      [](const BlockEstimate& e) { return e.derived.gain_std; });
  chart(
      "natural frequency fn (Hz)", [](const BlockEstimate& e) { return e.derived.fn_hz; },
      [](const BlockEstimate& e) { return e.derived.fn_hz_std; });
  chart(
      "damping ratio zeta", [](const BlockEstimate& e) { return e.derived.zeta; },
      [](const BlockEstimate& e) { return e.derived.zeta_std; });
}

void deviation(report::HtmlReport& page, const SessionData& d) {
  if (d.trace.t_s.empty()) return;
  report::Chart c{"Power deviation against the band",
                  "test time (s)",
                  "% of P0",
                  d.trace.t_s,
                  {},
                  {},
                  false,
                  false,
                  280};
  const double band = d.config.safety.band_pct;
  c.series.push_back({"(P - P0) / P0", d.trace.deviation_pct, "", false, false, 1.0});
  c.series.push_back(
      {"+band", std::vector<double>(d.trace.t_s.size(), band), "#d62728", true, false, 1.5});
  c.series.push_back(
      {"-band", std::vector<double>(d.trace.t_s.size(), -band), "#d62728", true, false, 1.5});
  c.series.push_back({"bias u (%)", d.trace.u_pct, "#7f7f7f", false, false, 1.0});
  page.section("Safety").chart(c);
  report::Table t{{"t (s)", "kind", "event"}, {}, {}};
  for (const auto& e : d.events) t.rows.push_back({fmt::format("{:.2f}", e.t_s), e.kind, e.text});
  if (!t.rows.empty()) page.table(t);
}

// Histogram (log counts: the tail matters) and the largest value of every second.
void loop_timing(report::HtmlReport& page, const SessionData& d) {
  if (!d.loop_timing || d.loop_timing->cycles == 0) return;
  const LoopTimingSummary& t = *d.loop_timing;
  const bool rt = t.mode == "realtime";
  const std::string what = rt ? "cycle start lateness (ms)" : "exchange wall time (ms)";
  page.section("Loop timing").paragraph(loop_timing_text(t));
  report::Chart h{
      rt ? "Lateness of the cycle start against the schedule" : "Wall time per exchange",
      what,
      "cycles",
      {},
      {},
      {},
      false,
      true,
      240};
  report::Series counts{"cycles", {}, "", false, true, 1.5};
  for (std::size_t i = 0; i < t.histogram.counts.size(); ++i) {
    h.x.push_back((static_cast<double>(i) + 0.5) * t.histogram.bin_ms);
    counts.y.push_back(t.histogram.counts[i] > 0.0 ? t.histogram.counts[i] : kNaN);
  }
  h.series = {counts};
  if (!h.x.empty()) page.chart(h);
  report::Chart s{"Largest " + what + " in each second",
                  "test time (s)",
                  "ms",
                  t.second_t_s,
                  {},
                  {},
                  false,
                  false,
                  220};
  s.series = {{"max", t.second_max_ms, "", false, false, 1.0}};
  if (!s.x.empty()) page.chart(s);
}

}  // namespace

void write_report_html(const SessionData& d, const std::filesystem::path& path) {
  report::HtmlReport page(fmt::format("rig {}: {}", d.command, d.link_uri));
  summary(page, d);
  bode(page, d);
  correlations(page, d);
  convergence(page, d);
  deviation(page, d);
  loop_timing(page, d);
  page.write(path);
}

}  // namespace rig::session
