// Which rows of a recording `rig identify` uses (--rows auto|all|excitation).
//
// A recording from `rig commission` has a `phase` column (0 steady, 1 pilot, 2 excite,
// 3 sweep; the sidecar's `phase_codes` name them). Only the excitation phase is the
// identification experiment: the steady state has no input, the pilot another amplitude, the
// swept sine a sinusoid at one frequency at a time and the ramps steps. So by default (auto)
// such a recording is cut to the longest contiguous run of excitation rows; --rows all uses
// every row; a recording without a phase column is used whole.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "rig/io/recording.hpp"

namespace rig::cli {

struct RowSelection {
  std::string mode = "all";  // "all" or "excitation"
  std::string reason;        // one sentence for the summary and the reports
  Eigen::Index first = 0;    // 0-based data row
  Eigen::Index count = 0;
  Eigen::Index total = 0;         // data rows in the file
  std::optional<int> phase_code;  // the excitation code, when the recording has phases
};

// rows_arg: "auto", "all" or "excitation" (InputError otherwise, or for "excitation" on a
// recording without excitation rows). `rec` is the recording as read for the input/output.
RowSelection select_rows(const std::filesystem::path& path, const io::Recording& rec,
                         const std::string& rows_arg);

// The rows [first, first + count) of every column (and of the time column).
io::Recording slice_rows(const io::Recording& rec, const RowSelection& rows);

}  // namespace rig::cli
