#include "rig/cli/identify_rows.hpp"

#include <fmt/format.h>

#include <cmath>

namespace rig::cli {
namespace {

// The code of the excitation phase: the sidecar's phase_codes entry named "excite", else 2.
int excitation_code(const io::Sidecar& sidecar) {
  const auto it = sidecar.raw.find("phase_codes");
  if (it != sidecar.raw.end() && it->is_object()) {
    for (const auto& [code, name] : it->items()) {
      if (name == "excite") {
        try {
          return std::stoi(code);
        } catch (const std::exception&) {
          break;
        }
      }
    }
  }
  return 2;
}

// The recording's phase column (full length), or nothing when it has none.
std::optional<Eigen::VectorXd> phase_column(const std::filesystem::path& path,
                                            const io::Recording& rec) {
  if (rec.has("phase")) return rec.column("phase");
  io::ReadOptions ro;
  ro.columns = {"phase"};
  ro.dt_s = rec.dt_s;
  ro.min_rows = 1;
  ro.read_sidecar = false;
  try {
    io::Recording p = io::read_recording(path, ro);
    if (p.rows() != rec.rows()) return std::nullopt;
    return p.columns[0];
  } catch (const io::InputError&) {
    return std::nullopt;  // no (numeric) phase column: not a commissioning recording
  }
}

}  // namespace

RowSelection select_rows(const std::filesystem::path& path, const io::Recording& rec,
                         const std::string& rows_arg) {
  if (rows_arg != "auto" && rows_arg != "all" && rows_arg != "excitation") {
    throw io::InputError("rig identify", 0, "",
                         "--rows: expected auto, all or excitation, found \"" + rows_arg + "\"");
  }
  RowSelection s;
  s.total = rec.rows();
  s.count = rec.rows();
  if (rows_arg == "all") {
    s.reason = "every row (--rows all)";
    return s;
  }
  const auto phase = phase_column(path, rec);
  if (!phase) {
    if (rows_arg == "excitation") {
      throw io::InputError(rec.source, 0, "phase",
                           "--rows excitation needs a phase column (a rig commission recording)");
    }
    s.reason = "every row (no phase column)";
    return s;
  }
  const int code = excitation_code(rec.sidecar);
  s.phase_code = code;
  // Longest contiguous run of rows with phase == code.
  Eigen::Index best_first = 0, best_count = 0, run_first = 0, run = 0;
  for (Eigen::Index i = 0; i < phase->size(); ++i) {
    if (std::lround((*phase)(i)) == code) {
      if (run == 0) run_first = i;
      if (++run > best_count) {
        best_count = run;
        best_first = run_first;
      }
    } else {
      run = 0;
    }
  }
  if (best_count == 0) {
    if (rows_arg == "excitation") {
      throw io::InputError(rec.source, 0, "phase",
                           fmt::format("--rows excitation: no row has phase = {}", code));
    }
    s.reason = fmt::format("every row (phase column without excitation rows, phase = {})", code);
    return s;
  }
  s.mode = "excitation";
  s.first = best_first;
  s.count = best_count;
  s.reason = fmt::format(
      "excitation phase only (phase = {}): rows {}-{} of {}, the longest "
      "contiguous run; --rows all uses every row",
      code, best_first + 1, best_first + best_count, s.total);
  return s;
}

io::Recording slice_rows(const io::Recording& rec, const RowSelection& rows) {
  if (rows.first == 0 && rows.count == rec.rows()) return rec;
  io::Recording out = rec;
  for (std::size_t i = 0; i < rec.columns.size(); ++i) {
    out.columns[i] = rec.columns[i].segment(rows.first, rows.count).eval();
  }
  if (rec.time_s) out.time_s = rec.time_s->segment(rows.first, rows.count).eval();
  out.first_data_line = rec.first_data_line + static_cast<long>(rows.first);
  return out;
}

}  // namespace rig::cli
