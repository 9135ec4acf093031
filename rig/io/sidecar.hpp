// The sidecar JSON of a recording: `rec.csv` -> `rec.json` (DESIGN.md section 5).
//
//   {
//     "sample_rate_hz": 100,                       // number > 0
//     "units": {"t": "s", "u": "%", "y": "kW"},    // column -> unit
//     "operating_point": {"power_kw": 3500},       // free-form object
//     "coupling_rc_s": 1.59,                       // AC-coupling time constant RC (s)
//     "coupled_columns": ["u_ac", "y_ac"],         // columns passed through that network
//     "link": "tcp://127.0.0.1:1502",
//     "preset": "stornoway",
//     "seed": 42                                   // unsigned integer
//   }
// Every key is optional; unknown keys are kept in `raw` and written back unchanged.
//
// A sample_rate_hz that contradicts the recording's own time base (its time column, or a
// Ts/fs column) by more than 1 % is refused when the recording is read (recording.hpp).
// The file must be a regular file of at most kMaxSidecarBytes; a UTF-8 byte-order mark is
// allowed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace rig::io {

// Metadata holds a few hundred bytes; the bound only keeps a wrong file from filling memory.
inline constexpr std::size_t kMaxSidecarBytes = 16u << 20;

struct Sidecar {
  bool present = false;
  std::string source;  // the file it was read from (for messages); not written back
  std::optional<double> sample_rate_hz;
  std::map<std::string, std::string> units;
  nlohmann::json operating_point = nlohmann::json::object();
  std::optional<double> coupling_rc_s;
  std::vector<std::string> coupled_columns;
  std::string link;
  std::string preset;
  std::optional<std::uint64_t> seed;
  // How long after a row's u was written its y was sampled (lockstep: one sample period;
  // real time: 0). Identified dead times refer to the plant with it (docs/decisions.md).
  std::optional<double> y_sampled_after_s;
  nlohmann::json raw = nlohmann::json::object();  // the whole document as read
};

// `rec.csv` -> `rec.json` (same folder, same stem).
std::filesystem::path sidecar_path(const std::filesystem::path& recording);

// Parses and validates (types and ranges); InputError naming the file and the key.
Sidecar parse_sidecar(const nlohmann::json& doc, const std::string& source);
Sidecar read_sidecar(const std::filesystem::path& path);

nlohmann::json to_json(const Sidecar& sidecar);
// Written to a temporary file and renamed, so a reader never sees half a sidecar.
void write_sidecar(const std::filesystem::path& path, const Sidecar& sidecar);

}  // namespace rig::io
