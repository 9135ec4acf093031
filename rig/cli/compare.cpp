// `rig compare`: a model against a measured frequency response (DESIGN.md section 4).
// Exit 0 when every checked point is within tolerance, 1 when not (or too few points are
// good enough to judge), 2 for unreadable input.
#include "rig/fra/compare.hpp"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <complex>
#include <filesystem>
#include <memory>

#include "rig/cli/session_commands.hpp"
#include "rig/io/exit_code.hpp"
#include "rig/io/input_error.hpp"
#include "rig/io/out_dir.hpp"
#include "rig/model/frf_file.hpp"
#include "rig/model/model_file.hpp"
#include "rig/report/bode_chart.hpp"
#include "rig/report/html_report.hpp"
#include "rig/report/json_out.hpp"

namespace rig::cli {
namespace {

struct CompareArgs {
  std::filesystem::path model, frf, out;
  fra::CompareTolerances tol;
  bool json = false;
  bool force = false;
};

nlohmann::json result_json(const CompareArgs& a, const fra::CompareResult& r) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& row : r.rows) {
    rows.push_back({{"freq_hz", row.freq_hz},
                    {"model_mag", report::number_or_null(row.model_mag)},
                    {"model_phase_deg", report::number_or_null(row.model_phase_deg)},
                    {"mag_error_db", report::number_or_null(row.mag_error_db)},
                    {"phase_error_deg", report::number_or_null(row.phase_error_deg)},
                    {"checked", row.checked},
                    {"pass", row.pass}});
  }
  return {{"command", "compare"},
          {"model", a.model.string()},
          {"frf", a.frf.string()},
          {"tolerances",
           {{"mag_db", a.tol.mag_db},
            {"phase_deg", a.tol.phase_deg},
            {"from_hz", a.tol.f_lo_hz},
            {"to_hz", a.tol.f_hi_hz},
            {"min_coherence", a.tol.min_coherence}}},
          {"verdict", fra::to_string(r.verdict)},
          {"checked", r.checked},
          {"failed", r.failed},
          {"max_abs_mag_error_db", report::number_or_null(r.max_abs_mag_error_db)},
          {"max_abs_phase_error_deg", report::number_or_null(r.max_abs_phase_error_deg)},
          {"summary", r.summary},
          {"rows", rows}};
}

void write_html(const CompareArgs& a, const model::TransferFunction& tf,
                const std::vector<model::FrfPoint>& pts, const fra::CompareResult& r) {
  std::vector<double> f;
  std::vector<std::complex<double>> model, measured;
  for (const auto& p : pts) {
    f.push_back(p.freq_hz);
    model.push_back(tf.response(p.freq_hz));
    measured.push_back(p.value());
  }
  report::HtmlReport page("rig compare: " + a.model.filename().string() + " vs " +
                          a.frf.filename().string());
  page.note(r.verdict == fra::Verdict::kPass ? report::Tone::kOk : report::Tone::kWarning,
            r.summary);
  auto [mag, phase] = report::bode_charts(
      "Model vs measured", f,
      {{"model", model, {}, {}, false, ""}, {"measured", measured, {}, {}, true, ""}});
  page.section("Frequency response").chart(mag).chart(phase);
  report::Table t{{"freq (Hz)", "mag error (dB)", "phase error (deg)", "checked", "pass"}, {}, {}};
  for (const auto& row : r.rows) {
    t.rows.push_back({fmt::format("{:.3f}", row.freq_hz), fmt::format("{:+.2f}", row.mag_error_db),
                      fmt::format("{:+.1f}", row.phase_error_deg), row.checked ? "yes" : "no",
                      row.pass ? "yes" : "no"});
  }
  page.section("Points").table(t);
  page.write(a.out / "report.html");
}

int run_compare(const CompareArgs& a) {
  io::prepare_out_dir(a.out, a.force);
  const model::TransferFunction tf = model::read_model(a.model).tf;
  // Every field of the file, the estimator's `valid` verdict included, so that this judges
  // exactly the points the commissioning session judged on the same sweep.csv.
  const model::Frf pts = model::read_frf(a.frf);
  const fra::CompareResult r = fra::compare(tf, pts, a.tol);
  const nlohmann::json doc = result_json(a, r);
  report::write_json_file(a.out / "report.json", doc);
  write_html(a, tf, pts, r);
  if (a.json) {
    fmt::print("{}\n", doc.dump(2));
  } else {
    fmt::print("rig compare: {}\n  report: {}\n", r.summary, (a.out / "report.html").string());
  }
  return r.verdict == fra::Verdict::kPass ? 0 : 1;
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto a = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand("compare", "Compare a model with a measured FRF");
  cmd->add_option("--model", a->model, "Model JSON")->required();
  cmd->add_option("--frf", a->frf,
                  "FRF CSV (freq_hz,mag,phase_deg,coherence[,mag_lo,mag_hi][,valid])")
      ->required();
  cmd->add_option("--out", a->out, "Output folder (must be new or empty, see --force)")->required();
  cmd->add_flag("--force", a->force,
                "Clear a non-empty --out folder first (an earlier run's files)");
  cmd->add_option("--mag-tol-db", a->tol.mag_db, "Magnitude tolerance, dB")->default_val(1.0);
  cmd->add_option("--phase-tol-deg", a->tol.phase_deg, "Phase tolerance, deg")->default_val(5.0);
  cmd->add_option("--from", a->tol.f_lo_hz, "Check from, Hz")->default_val(0.5);
  cmd->add_option("--to", a->tol.f_hi_hz, "Check to, Hz")->default_val(5.0);
  cmd->add_option("--min-coherence", a->tol.min_coherence, "Ignore points below")->default_val(0.8);
  cmd->add_flag("--json", a->json, "Print report.json on stdout");
  cmd->callback([a] {
    const int code = run_compare(*a);
    if (code != kExitOk) throw CLI::RuntimeError(code);
  });
}

}  // namespace rig::cli
