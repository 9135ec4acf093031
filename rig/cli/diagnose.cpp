// rig diagnose --recording REC.csv --model MODEL.json --out DIR
//              [--input COL --output COL | --columns I,J] [--bus-frequency COL|none]
//              [--dt S] [--no-pairs] [--json]
// Why a model and a recording disagree (DESIGN.md sections 4 and 9). Writes report.json,
// report.html and augmented_model.json. Exit 0 when the diagnosis ran (whatever the
// verdict), 2 for bad input (one line naming the file/field and what was expected).
// The model is a transfer-function JSON or a plantsim TOML plant: the plant is linearised by
// the plantsim executable beside the rig, the diagnosis runs against that transfer function,
// and the effects found are written back as plant parameters (augmented_plant.toml) and
// checked by replaying the recorded bias through both plants (diagnose_plant.hpp).
#include "rig/cli/diagnose.hpp"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include "rig/cli/commands.hpp"
#include "rig/cli/diagnose_plant.hpp"
#include "rig/diagnose/diagnose.hpp"
#include "rig/diagnose/report_out.hpp"
#include "rig/io/input_error.hpp"
#include "rig/io/out_dir.hpp"
#include "rig/io/recording.hpp"
#include "rig/model/model_file.hpp"
#include "rig/report/html_report.hpp"
#include "rig/report/json_out.hpp"
#include "rig/session/emulator.hpp"
#include "rig/signal/ac_coupling.hpp"

namespace rig::cli {
namespace {

struct DiagnoseArgs {
  std::filesystem::path recording, model, out;
  std::string input, output, columns;
  std::string bus_frequency;  // a column, "none", or empty: freq_hz when the header has it
  std::optional<double> dt_s;
  bool no_pairs = false, json = false, no_plant_check = false, force = false;
};

[[noreturn]] void bad(const std::string& file, const std::string& field, const std::string& what) {
  throw io::InputError(file, 0, field, what);
}

// Whether the recording's header row names `column` (a headerless file names none).
bool header_has(const std::filesystem::path& path, const std::string& column) {
  std::ifstream f(path);
  std::string line;
  if (!std::getline(f, line)) return false;
  std::string name;
  for (std::size_t i = 0; i <= line.size(); ++i) {
    const char c = i < line.size() ? line[i] : ',';
    if (c == ',' || c == ';' || c == '\t' || c == '\r') {
      if (name == column) return true;
      name.clear();
    } else if (c != '"' && c != ' ') {
      name += c;
    }
  }
  return false;
}

// The bus frequency's column (DESIGN.md 5): --bus-frequency COL, or freq_hz when the
// recording has it; "none" or nothing.
std::string bus_frequency_column(const DiagnoseArgs& a) {
  if (a.bus_frequency == "none") return "";
  if (!a.bus_frequency.empty()) return a.bus_frequency;
  return header_has(a.recording, "freq_hz") ? "freq_hz" : "";
}

io::Recording load(const DiagnoseArgs& a, std::string& in, std::string& out,
                   const std::string& bus) {
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
  if (!bus.empty()) ro.columns.push_back(bus);
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

void check_units(const io::Recording& rec, const model::ModelFile& m, const std::string& model_file,
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
// coupler and the input column did not (a coupled pair keeps the linear relation). A
// coupling that names no columns is the rig's matched coupling of raw columns (what
// `rig commission` writes): the recorded u and y are raw, so nothing applies.
std::optional<double> output_coupling(const io::Recording& rec, const std::string& in,
                                      const std::string& out) {
  const auto& sc = rec.sidecar;
  if (!sc.coupling_rc_s) return std::nullopt;
  const auto has = [&](const std::string& c) {
    return std::find(sc.coupled_columns.begin(), sc.coupled_columns.end(), c) !=
           sc.coupled_columns.end();
  };
  if (sc.coupled_columns.empty()) return std::nullopt;
  return has(out) && !has(in) ? sc.coupling_rc_s : std::nullopt;
}

// A model of the plant's physics (a plant TOML, a JSON from `plantsim --linearise`, which
// names its source plant, or the model `rig commission` writes, "timing": "plant") relates
// u(t) and y(t) in continuous time; the rows hold each u for
// a sample (zero-order hold: half a sample of dead time) and may carry y sampled after the
// row's u was written (sidecar y_sampled_after_s: one sample in lockstep). Identified
// models have both in their delay already and are used as they are.
bool physical_model(const model::ModelFile& m, bool plant_toml) {
  const auto& x = m.extra;
  return plant_toml ||
         (x.contains("source") && x["source"].is_object() && x["source"].contains("plant")) ||
         (x.contains("timing") && x["timing"] == "plant");
}

double row_alignment_s(const io::Recording& rec) {
  return 0.5 * rec.dt_s - rec.sidecar.y_sampled_after_s.value_or(0.0);
}

int run_diagnose(const DiagnoseArgs& a) {
  const bool plant_toml = a.model.extension().string() == ".toml";
  io::prepare_out_dir(a.out, a.force);
  std::string in, out;
  const std::string bus = bus_frequency_column(a);
  const io::Recording rec = load(a, in, out, bus);
  std::optional<TempDir> tmp;
  std::optional<PlantModel> plant;
  if (plant_toml) {
    tmp.emplace();
    plant = load_plant_model(a.model, session::default_plantsim_path(), *tmp);
  }
  model::ModelFile model = plant ? plant->linear : model::read_model(a.model);
  const double alignment_s = physical_model(model, plant_toml) ? row_alignment_s(rec) : 0.0;
  model.tf.delay_s += alignment_s;
  if (model.tf.delay_s < 0.0)
    bad(a.model.string(), "delay_s",
        fmt::format("the model's dead time is shorter than the recording's row alignment "
                    "({:.4g} s)",
                    -alignment_s));
  check_units(rec, model, a.model.string(), in, out);
  if (!model.tf.is_stable())
    bad(a.model.string(), "den",
        "expected a stable model (every pole in the open left half plane)");
  // The recording chain's coupling; a plant's own AC coupling (meas.ac_rc_s) is not in its
  // linearisation, so it is applied here instead.
  const std::optional<double> chain_rc = output_coupling(rec, in, out);
  const double plant_rc = plant ? plant->param("meas.ac_rc_s") : 0.0;
  diagnose::DiagnoseInput di{model.tf, rec.column(in), rec.column(out), rec.dt_s,
                             plant_rc > 0.0 ? std::optional(plant_rc) : chain_rc};
  if (!bus.empty()) di.bus_freq_hz = rec.column(bus);
  diagnose::DiagnoseOptions opt;
  opt.try_pairs = !a.no_pairs;
  diagnose::DiagnoseResult r;
  try {
    r = diagnose::diagnose(di, opt);
  } catch (const std::invalid_argument& e) {
    bad(a.recording.string(), "", e.what());
  }
  const diagnose::ReportContext ctx{a.recording.string(), a.model.string(), in, out};
  nlohmann::json doc = diagnose::report_json(r, ctx);
  doc["model_alignment_s"] = alignment_s;
  std::vector<std::string> plant_lines;
  PlantPage plant_page;
  if (plant) {
    const PlantOutputInput pi{*plant,
                              *tmp,
                              r,
                              model.tf,
                              di.u,
                              di.y,
                              rec.dt_s,
                              plant_rc > 0.0 ? std::nullopt : chain_rc,
                              a.out,
                              a.recording.string(),
                              !a.no_plant_check};
    doc.update(write_plant_outputs(pi, &plant_lines, &plant_page));
  }
  report::write_json_file(a.out / "report.json", doc);
  diagnose::write_report_html(r, ctx, a.out / "report.html", [&](report::HtmlReport& html) {
    if (plant) plant_section(html, plant_page);
  });
  model::write_model(a.out / "augmented_model.json", diagnose::augmented_model(r, model));
  if (a.json) {
    fmt::print("{}\n", doc.dump(2));
  } else {
    fmt::print("rig diagnose: verdict {}\n  {}\n", r.verdict, r.explanation);
    for (const auto& l : plant_lines) fmt::print("  {}\n", l);
    fmt::print("  report: {}\n", (a.out / "report.html").string());
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
  cmd->add_option("--model", a->model,
                  "Transfer-function model JSON, or a plantsim plant TOML (linearised by the "
                  "plantsim beside rig; also writes augmented_plant.toml)")
      ->required();
  cmd->add_option("--input", a->input, "Input column (default u)");
  cmd->add_option("--output", a->output, "Output column (default y)");
  cmd->add_option("--columns", a->columns, "Input and output columns by 1-based index: I,J")
      ->excludes(cmd->get_option("--input"))
      ->excludes(cmd->get_option("--output"));
  cmd->add_option("--bus-frequency", a->bus_frequency,
                  "Bus frequency column (Hz): the grid's share of the output is taken out "
                  "first when the bias does not move it (default freq_hz when the recording "
                  "has it; none: do not use one)");
  cmd->add_option("--dt", a->dt_s, "Sample period in s (overrides the time column and sidecar)");
  cmd->add_option("--out", a->out, "Output folder (must be new or empty, see --force)")->required();
  cmd->add_flag("--force", a->force,
                "Clear a non-empty --out folder first (an earlier run's files)");
  cmd->add_flag("--no-pairs", a->no_pairs, "Do not try pairs of effects");
  cmd->add_flag("--no-plant-check", a->no_plant_check,
                "With a plant TOML: skip replaying the recording through the plants");
  cmd->add_flag("--json", a->json, "Print report.json on stdout instead of the summary");
  cmd->callback([a] {
    const int code = run_diagnose(*a);
    if (code != kExitOk) throw CLI::RuntimeError(code);
  });
}

}  // namespace rig::cli
