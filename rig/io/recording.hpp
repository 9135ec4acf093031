// Recordings (DESIGN.md section 5): a table of equally long numeric columns sampled at a
// uniform rate, from
//   * a CSV with a header row (any column names; separators ',' ';' or tab), including the
//     MATLAB quirks of the public benchmark files: quoted header, a trailing comma on every
//     row, blank trailing lines, and "scalar" columns (Ts, fs) holding a value in the first
//     data row only;
//   * a whitespace-separated `.dat` (or any file whose first line is all numbers) without a
//     header; its columns are named "1", "2", ... (1-based, as `cut -f` counts);
// plus an optional sidecar JSON with the same stem (see sidecar.hpp).
//
// Time base, in order of precedence: ReadOptions::dt_s (--dt), the time column ("t",
// "t_s", "time" or "time_s"; its mean step), the sidecar's sample_rate_hz, a scalar column
// Ts / fs / Fs. Timestamps are kept so that the jitter can be reported.
//
// A last line without a terminating newline is a partially written row (the writer was
// killed mid-write): it is dropped with a warning. Every other defect throws InputError.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "rig/io/input_error.hpp"
#include "rig/io/sidecar.hpp"

namespace rig::io {

struct ReadOptions {
  // Columns to keep (by name, or 1-based index for headerless files); empty = all. Only
  // kept columns (and the time column) are validated, so unrelated text columns such as a
  // status word do not make a recording unreadable.
  std::vector<std::string> columns;
  std::optional<double> dt_s;     // overrides every other time base
  Eigen::Index min_rows = 2;      // fewer data rows -> InputError
  double jitter_tolerance = 0.01; // |t step - dt| / dt above this -> sampling.uniform = false
  bool read_sidecar = true;
  bool require_time_base = true;  // InputError when no dt can be found
};

// Uniformity of the time column: steps d_i = t_{i+1} - t_i against dt = (t_N - t_1)/(N-1).
struct SamplingCheck {
  bool has_time = false;      // false: dt came from options/sidecar/scalar, nothing to check
  double dt_s = 0.0;
  double jitter_rms_s = 0.0;  // rms of d_i - dt
  double jitter_max_s = 0.0;  // max |d_i - dt|
  bool uniform = true;        // jitter_max_s <= jitter_tolerance * dt_s
  std::string dt_source;      // "option", "time column", "sidecar", "scalar column Ts"...
};

struct Recording {
  std::string source;                       // file name used in messages
  std::vector<std::string> names;           // kept data columns (time column excluded)
  std::vector<Eigen::VectorXd> columns;     // same order as names, all rows() long
  std::optional<Eigen::VectorXd> time_s;    // the time column, when there is one
  std::string time_name;                    // its header name
  std::map<std::string, double> scalars;    // first-row-only columns (Ts, fs, ...)
  double dt_s = 0.0;
  SamplingCheck sampling;
  Sidecar sidecar;                          // empty when there is none
  bool has_header = false;
  long first_data_line = 1;                 // file line of row 0 (rows are contiguous)
  std::vector<std::string> warnings;        // e.g. the dropped partial last line

  Eigen::Index rows() const { return columns.empty() ? 0 : columns.front().size(); }
  bool has(const std::string& name) const;
  // The named column, or InputError naming the file, the column and the columns present.
  const Eigen::VectorXd& column(const std::string& name) const;
};

// Reads `path` (and its sidecar `path.stem().json` when present and options.read_sidecar).
Recording read_recording(const std::filesystem::path& path, const ReadOptions& options = {});

// Parses recording text already in memory; `source` names it in messages. No sidecar.
Recording parse_recording(std::string_view text, const std::string& source,
                          const ReadOptions& options = {});

// The 1-based column name for headerless files ("3" for index 3).
std::string index_column_name(int index_1based);

}  // namespace rig::io
