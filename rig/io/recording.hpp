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
// Sidecar against the file (decision): a sidecar's sample_rate_hz is a second statement of
// the rate, and when it contradicts the file's own time base (the time column's mean step,
// else a Ts/fs column) one of the two is wrong and the reader cannot tell which, so the
// recording is refused, naming the sidecar, the key and both figures:
//     rec.json: key "sample_rate_hz": expected 50 Hz as the time column "t" of rec.csv says
//     (mean step 0.02 s), found 100 Hz; ...
// They agree when the periods differ by at most kSampleRateTolerance (1 %) of the file's
// period: clock drift and rounding of a written rate (ppm to 0.1 %) pass, a wrong rate (a
// factor of 2 or 10, 50 against 60 Hz) does not. Dropped samples (gaps) lengthen the mean
// step too and can make a true sidecar disagree; the message gives both figures, and
// --dt (ReadOptions::dt_s) is the user's explicit decision and overrides both: then the
// contradiction is only a warning.
//
// Robustness: the input must be a regular file (a FIFO or /dev/zero is refused, see
// InputFile); a UTF-8 byte-order mark at the start is skipped (a UTF-16 one is refused: the
// file must be UTF-8 or ASCII); a line longer than kMaxLineBytes is an error naming the line,
// so a file without line ends cannot fill memory. The file is read and parsed in chunks of
// 1 MiB: only the parsed doubles of the columns that can be kept are held (their storage
// reserved from the file size), so the peak memory is about the parsed data (measured by
// build/bin/bench_recording_memory), not the text plus the data.
//
// A last line without a terminating newline is a partially written row (the writer was
// killed mid-write): it is dropped with a warning. Every other defect throws InputError.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rig/io/input_error.hpp"
#include "rig/io/sidecar.hpp"

namespace rig::io {

// Longest accepted line (without its line end); a longer one is an InputError naming it.
inline constexpr std::size_t kMaxLineBytes = 64u * 1024u;
// Largest relative difference of the sidecar's sample period from the file's own (see above).
inline constexpr double kSampleRateTolerance = 0.01;

struct ReadOptions {
  // Columns to keep (by name, or 1-based index for headerless files); empty = all. Only
  // kept columns (and the time column) are validated, so unrelated text columns such as a
  // status word do not make a recording unreadable.
  std::vector<std::string> columns;
  std::optional<double> dt_s;      // overrides every other time base
  Eigen::Index min_rows = 2;       // fewer data rows -> InputError
  double jitter_tolerance = 0.01;  // |t step - dt| / dt above this -> sampling.uniform = false
  bool read_sidecar = true;
  bool require_time_base = true;  // InputError when no dt can be found
};

// Uniformity of the time column: steps d_i = t_{i+1} - t_i against dt = (t_N - t_1)/(N-1).
struct SamplingCheck {
  bool has_time = false;  // false: dt came from options/sidecar/scalar, nothing to check
  double dt_s = 0.0;
  double jitter_rms_s = 0.0;  // rms of d_i - dt
  double jitter_max_s = 0.0;  // max |d_i - dt|
  bool uniform = true;        // jitter_max_s <= jitter_tolerance * dt_s
  std::string dt_source;      // "option", "time column", "sidecar", "scalar column Ts"...
};

struct Recording {
  std::string source;                     // file name used in messages
  std::vector<std::string> names;         // kept data columns (time column excluded)
  std::vector<Eigen::VectorXd> columns;   // same order as names, all rows() long
  std::optional<Eigen::VectorXd> time_s;  // the time column, when there is one
  std::string time_name;                  // its header name
  std::map<std::string, double> scalars;  // first-row-only columns (Ts, fs, ...)
  double dt_s = 0.0;
  SamplingCheck sampling;
  Sidecar sidecar;  // empty when there is none
  bool has_header = false;
  long first_data_line = 1;           // file line of row 0 (rows are contiguous)
  std::vector<std::string> warnings;  // e.g. the dropped partial last line

  Eigen::Index rows() const { return columns.empty() ? 0 : columns.front().size(); }
  bool has(const std::string& name) const;
  // The named column, or InputError naming the file, the column and the columns present.
  const Eigen::VectorXd& column(const std::string& name) const;
};

// Reads `path` (and its sidecar `path.stem().json` when present and options.read_sidecar),
// streamed in chunks.
Recording read_recording(const std::filesystem::path& path, const ReadOptions& options = {});

// Parses recording text already in memory; `source` names it in messages. No sidecar.
Recording parse_recording(std::string_view text, const std::string& source,
                          const ReadOptions& options = {});

// The 1-based column name for headerless files ("3" for index 3).
std::string index_column_name(int index_1based);

}  // namespace rig::io
