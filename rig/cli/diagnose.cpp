// rig diagnose --recording REC.csv --model MODEL.json --out DIR
//              [--input COL --output COL | --columns I,J] [--dt S] [--no-pairs] [--json]
// Why a model and a recording disagree (DESIGN.md sections 4 and 9). Writes report.json,
// report.html and augmented_model.json. Exit 0 when the diagnosis ran (whatever the
// verdict), 2 for bad input (one line naming the file/field and what was expected).
// The model is a transfer-function JSON; a plantsim TOML plant is not accepted yet.
#include "rig/cli/diagnose.hpp"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "rig/cli/commands.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/report_out.hpp"
#include "rig/io/input_error.hpp"
#include "rig/io/model_file.hpp"
#include "rig/io/recording.hpp"
#include "rig/report/json_out.hpp"

namespace rig::cli {
namespace {

struct DiagnoseArgs {
  std::filesystem::path recording, model, out;
  std::string input, output, columns;
  std::optional<double> dt_s;
  bool no_pairs = false, json = false;
};

[[noreturn]] void bad(const std::string& file, const std::string& field, const std::string& what) {
  throw io::InputError(file, 0, field, what);
}

io::Recording load(const DiagnoseArgs& a, std::string& in, std::string& out) {
  io::ReadOptions ro;
  ro.dt_s = a.dt_s;
  in = a.input, out = a.output;
  if (!a.columns.empty()) {
    const auto comma = a.columns.find(',');
    if (comma == std::string::npos) bad("rig diagnose", "--columns", "expected I,J (1-based)");
    in = a.columns.substr(0, comma), out = a.columns.substr(comma + 1);
  }
  if (in.empty() != out.empty())
    bad("rig diagnose", "--input/--output", "give both columns, or neither");
  if (in.empty()) in = "u", out = "y";
  ro.columns = {in, out};
  io::Recording rec = io::read_recording(a.recording, ro);
  in = rec.names[0], out = rec.names[1];
  if (!rec.sampling.uniform)
    bad(rec.source, rec.time_name,
        fmt::format("expected uniform sampling, found jitter up to {:.3g} s at dt {:.3g} s",
                    rec.sampling.jitter_max_s, rec.dt_s));
  if (rec.sidecar.sample_rate_hz && rec.sampling.has_time && !a.dt_s &&
      std::abs(1.0 / *rec.sidecar.sample_rate_hz - rec.dt_s) > 0.01 * rec.dt_s)
    bad(io::sidecar_path(a.recording).string(), "sample_rate_hz",
        fmt::format("expected {:.6g} Hz as the time column says, found {:.6g} Hz", 1.0 / rec.dt_s,
                    *rec.sidecar.sample_rate_hz));
  return rec;
}

// The first word of a unit, lower case ("% of rated power" -> "%").
std::string unit_word(const std::string& u) {
  std::string w = u.substr(0, u.find(' '));
  std::transform(w.begin(), w.end(), w.begin(), [](unsigned char c) { return std::tolower(c); });
  return w;
}

void check_units(const io::Recording& rec, const io::ModelFile& m, const std::string& model_file,
                 const std::string& in, const std::string& out) {
  if (!m.units.is_object()) return;
  const std::pair<const char*, const std::string*> sides[] = {{"input", &in}, {"output", &out}};
  for (const auto& [side, col] : sides) {
    const auto it = rec.sidecar.units.find(*col);
    if (!m.units.contains(side) || !m.units[side].is_string() || it == rec.sidecar.units.end())
      continue;
    const std::string mu = m.units[side].get<std::string>();
    if (unit_word(mu) != unit_word(it->second))
      bad(model_file, std::string("units.") + side,
          fmt::format("expected the recording's unit \"{}\" for column {}, found \"{}\"",
                      it->second, *col, mu));
  }
}

// The sidecar's coupling applies to the model when the output column went through the
// coupler and the input column did not (a coupled pair keeps the linear relation).
std::optional<double> output_coupling(const io::Recording& rec, const std::string& in,
                                      const std::string& out) {
  const auto& sc = rec.sidecar;
  if (!sc.coupling_rc_s) return std::nullopt;
  const auto has = [&](const std::string& c) {
    return std::find(sc.coupled_columns.begin(), sc.coupled_columns.end(), c) !=
           sc.coupled_columns.end();
  };
  if (sc.coupled_columns.empty()) return sc.coupling_rc_s;
  return has(out) && !has(in) ? sc.coupling_rc_s : std::nullopt;
}

int run_diagnose(const DiagnoseArgs& a) {
  const std::string ext = a.model.extension().string();
  if (ext == ".toml")
    bad(a.model.string(), "",
        "plantsim TOML plants are not supported by diagnose yet; give a "
        "transfer-function model JSON (e.g. plantsim's linearised *.tf.json)");
  std::string in, out;
  const io::Recording rec = load(a, in, out);
  const io::ModelFile model = io::read_model(a.model);
  check_units(rec, model, a.model.string(), in, out);
  if (!model.tf.is_stable())
    bad(a.model.string(), "den",
        "expected a stable model (every pole in the open left half plane)");
  diagnose::DiagnoseInput di{model.tf, rec.column(in), rec.column(out), rec.dt_s,
                             output_coupling(rec, in, out)};
  diagnose::DiagnoseOptions opt;
  opt.try_pairs = !a.no_pairs;
  diagnose::DiagnoseResult r;
  try {
    r = diagnose::diagnose(di, opt);
  } catch (const std::invalid_argument& e) {
    bad(a.recording.string(), "", e.what());
  }
  std::filesystem::create_directories(a.out);
  const diagnose::ReportContext ctx{a.recording.string(), a.model.string(), in, out};
  const nlohmann::json doc = diagnose::report_json(r, ctx);
  report::write_json_file(a.out / "report.json", doc);
  diagnose::write_report_html(r, ctx, a.out / "report.html");
  io::write_model(a.out / "augmented_model.json", diagnose::augmented_model(r, model));
  if (a.json) {
    fmt::print("{}\n", doc.dump(2));
  } else {
    fmt::print("rig diagnose: verdict {}\n  {}\n  report: {}\n", r.verdict, r.explanation,
               (a.out / "report.html").string());
  }
  return kExitOk;
}

}  // namespace

void add_diagnose_command(CLI::App& app) {
  auto a = std::make_shared<DiagnoseArgs>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose",
      "Find why a model and a recording disagree: locate the mismatch, fit the "
      "effects of DESIGN.md 9, write report.json, report.html, augmented_model.json");
  cmd->add_option("--recording", a->recording, "Recording CSV (sidecar JSON beside it is read)")
      ->required();
  cmd->add_option("--model", a->model, "Transfer-function model JSON")->required();
  cmd->add_option("--input", a->input, "Input column (default u)");
  cmd->add_option("--output", a->output, "Output column (default y)");
  cmd->add_option("--columns", a->columns, "Input and output columns by 1-based index: I,J")
      ->excludes(cmd->get_option("--input"))
      ->excludes(cmd->get_option("--output"));
  cmd->add_option("--dt", a->dt_s, "Sample period in s (overrides the time column and sidecar)");
  cmd->add_option("--out", a->out, "Output folder")->required();
  cmd->add_flag("--no-pairs", a->no_pairs, "Do not try pairs of effects");
  cmd->add_flag("--json", a->json, "Print report.json on stdout instead of the summary");
  cmd->callback([a] {
    int code = kExitUsage;
    try {
      code = run_diagnose(*a);
    } catch (const io::InputError& e) {
      fmt::print(stderr, "rig diagnose: {}\n", e.what());
    } catch (const std::invalid_argument& e) {
      fmt::print(stderr, "rig diagnose: {}\n", e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      fmt::print(stderr, "rig diagnose: {}\n", e.what());
    }
    if (code != kExitOk) throw CLI::RuntimeError(code);
  });
}

}  // namespace rig::cli
