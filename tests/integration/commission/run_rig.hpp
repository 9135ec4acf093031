// Runs build/bin/rig (and plantsim) from the integration tests.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace rig::testing {

std::filesystem::path bin_dir();
std::filesystem::path source_dir();
// A fresh folder under the test's temporary directory.
std::filesystem::path fresh_dir(const std::string& name);
// The log of a run whose --out is `out`: beside it, since --out must be new or empty.
inline std::filesystem::path log_beside(const std::filesystem::path& out) {
  return std::filesystem::path(out.string() + ".log");
}
// Runs `rig ARGS` with output to DIR/rig.log; returns the exit code (-1 when killed).
int run_rig(const std::string& args, const std::filesystem::path& log);
nlohmann::json read_json(const std::filesystem::path& path);
std::string read_text(const std::filesystem::path& path);

// Largest magnitude (dB) and phase (deg) errors of model.json against the plant's
// linearisation plantsim/presets/stornoway.tf.json over log-spaced 0.5-5 Hz.
struct TruthError {
  double max_db = 0.0;
  double max_deg = 0.0;
};
TruthError error_against_truth(const std::filesystem::path& model_json);

}  // namespace rig::testing
