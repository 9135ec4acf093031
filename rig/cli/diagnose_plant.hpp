// A plantsim TOML plant as the model of `rig diagnose` (docs/diagnose.md, "A plant TOML as
// the model"). The rig does not link the plant (DESIGN.md 3): the plantsim executable is run
// as a subprocess to linearise the plant (--linearise), to list its resolved parameters
// (--list-params) and to replay a recorded bias through it (--replay). The diagnosed effects
// are mapped back onto plant parameters (plant_changes()) and written as a plant TOML.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rig/diagnose/diagnose.hpp"
#include "rig/model/model_file.hpp"
#include "rig/model/transfer_function.hpp"

namespace rig::report {
class HtmlReport;
}  // namespace rig::report

namespace rig::cli {

// Exit status and combined stdout+stderr of a finished process.
struct ProcessResult {
  int exit_code = -1;
  std::string output;
};
// Runs argv[0] (a path) with the arguments; throws std::runtime_error if it cannot start.
ProcessResult run_process(const std::vector<std::string>& argv);

// A temporary folder, removed with its contents by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

struct PlantModel {
  std::filesystem::path toml;                               // the plant as given
  std::filesystem::path plantsim;                           // the executable used
  model::ModelFile linear;                                  // plantsim --linearise (bias % -> kW)
  std::map<std::string, double> params;                     // resolved "block.name" -> value
  std::map<std::string, std::pair<double, double>> ranges;  // valid range per key
  double param(const std::string& key) const;               // InputError naming the key when absent
};

// Linearises and lists the plant with `plantsim`; InputError naming `toml` (one line, with
// plantsim's own message) when plantsim rejects it or is missing.
PlantModel load_plant_model(const std::filesystem::path& toml,
                            const std::filesystem::path& plantsim, const TempDir& tmp);

// One plant parameter set from a diagnosed effect.
struct PlantChange {
  std::string key;  // "meas.transducer_lag_s"
  double old_value = 0.0, new_value = 0.0;
  std::string effect;  // "sensor_lag"
  std::string reason;  // one line: the effect parameter and the conversion
};
struct PlantMapping {
  std::vector<PlantChange> changes;
  std::vector<std::string> notes;  // effects with no plant parameter, clamped values
};

// The parameters that express a hypothesis' effects in the plant (each effect's mapping:
// rig/diagnose/effects/<word>.cpp). `baseline` is the model the effects were fitted against; `u`
// the recorded input (its mean is the operating bias the input limits are relative to).
PlantMapping plant_changes(const diagnose::HypothesisFit& hypothesis, const PlantModel& plant,
                           const model::TransferFunction& baseline, const Eigen::VectorXd& u);

// The input TOML with the changes applied (toml++; the original's comments are not kept)
// and a comment header naming each change and why; `summary` lines go into the header.
std::string augmented_plant_toml(const std::filesystem::path& input, const PlantMapping& mapping,
                                 const std::vector<std::string>& summary);

// plantsim --config TOML --replay: the plant's deterministic measured power (kW) for the
// bias u sampled at dt_s. std::runtime_error with plantsim's message on failure.
Eigen::VectorXd replay_plant(const std::filesystem::path& plantsim,
                             const std::filesystem::path& toml, const Eigen::VectorXd& u,
                             double dt_s, const TempDir& tmp);

// Everything the plant outputs of a diagnosis need.
struct PlantOutputInput {
  const PlantModel& plant;
  const TempDir& tmp;
  const diagnose::DiagnoseResult& result;
  const model::TransferFunction& baseline;  // as diagnosed
  const Eigen::VectorXd& u;                 // recorded input and output
  const Eigen::VectorXd& y;
  double dt_s = 0.01;
  std::optional<double> chain_rc_s;  // the recording chain's AC coupling of the output
  std::filesystem::path out_dir;
  std::string recording;
  bool plant_check = true;
};

// What report.html shows of the plant outputs (its "Plant" section).
struct PlantPage {
  std::string toml, augmented;  // the plant as given, the augmented plant written
  PlantMapping mapping;
  std::optional<double> fit_before_pct, fit_after_pct;  // the plant check, when replayed
  std::string check_error;
  Eigen::VectorXd y, before, after;  // recorded output and the two replays
  double dt_s = 0.01;
  Eigen::Index warmup = 0;
};

// Writes out_dir/augmented_plant.toml and, with plant_check, out_dir/plant_check.csv
// (t, u, y, the replayed plant before and after); returns the report.json keys
// `plant_model` and `plant_check`, appends summary lines and fills page.
nlohmann::json write_plant_outputs(const PlantOutputInput& in, std::vector<std::string>* summary,
                                   PlantPage* page);

// report.html's "Plant" section: the parameters written back, the notes of the mapping, and
// the plant check's replays against the recording.
void plant_section(report::HtmlReport& html, const PlantPage& page);

}  // namespace rig::cli
