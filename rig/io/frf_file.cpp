#include "rig/io/frf_file.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "rig/io/atomic_file.hpp"
#include "rig/io/recording.hpp"

namespace rig::io {
namespace {

// "" when valid, else what is wrong (first offending row, 0-based).
std::string frf_problem(const Frf& f, Eigen::Index& row, std::string& column) {
  const Eigen::Index n = f.freq_hz.size();
  if (f.mag.size() != n || f.phase_deg.size() != n || f.coherence.size() != n ||
      (f.mag_lo && f.mag_lo->size() != n) || (f.mag_hi && f.mag_hi->size() != n) ||
      bool(f.mag_lo) != bool(f.mag_hi)) {
    return "columns of different lengths (or only one of mag_lo/mag_hi)";
  }
  for (row = 0; row < n; ++row) {
    if (!(f.freq_hz[row] > 0.0) || (row > 0 && !(f.freq_hz[row] > f.freq_hz[row - 1]))) {
      column = "freq_hz";
      return "expected frequencies > 0 and strictly increasing";
    }
    if (!(f.mag[row] >= 0.0)) {
      column = "mag";
      return "expected a magnitude >= 0";
    }
    if (!(f.coherence[row] >= 0.0 && f.coherence[row] <= 1.0 + 1e-9)) {
      column = "coherence";
      return "expected a coherence in [0, 1]";
    }
  }
  return "";
}

}  // namespace

Frf read_frf(const std::filesystem::path& path) {
  ReadOptions options;
  options.read_sidecar = false;
  options.require_time_base = false;
  options.min_rows = 1;
  Recording table = read_recording(path, options);
  if (!table.has_header) throw InputError(path.string(), 1, "", "expected a header row");
  Frf f;
  f.freq_hz = table.column("freq_hz");
  f.mag = table.column("mag");
  f.phase_deg = table.column("phase_deg");
  f.coherence = table.column("coherence");
  if (table.has("mag_lo") || table.has("mag_hi")) {
    f.mag_lo = table.column("mag_lo");
    f.mag_hi = table.column("mag_hi");
  }
  Eigen::Index row = 0;
  std::string column;
  if (const std::string problem = frf_problem(f, row, column); !problem.empty()) {
    throw InputError(path.string(), table.first_data_line + long(row), column, problem);
  }
  return f;
}

void write_frf(const std::filesystem::path& path, const Frf& frf) {
  Eigen::Index row = 0;
  std::string column;
  if (const std::string problem = frf_problem(frf, row, column); !problem.empty()) {
    throw std::invalid_argument(fmt::format("FRF row {} {}: {}", row, column, problem));
  }
  std::string text = frf.mag_lo ? "freq_hz,mag,phase_deg,coherence,mag_lo,mag_hi\n"
                                : "freq_hz,mag,phase_deg,coherence\n";
  for (Eigen::Index i = 0; i < frf.size(); ++i) {
    fmt::format_to(std::back_inserter(text), "{:.10g},{:.10g},{:.10g},{:.6g}", frf.freq_hz[i],
                   frf.mag[i], frf.phase_deg[i], frf.coherence[i]);
    if (frf.mag_lo) {
      fmt::format_to(std::back_inserter(text), ",{:.10g},{:.10g}", (*frf.mag_lo)[i],
                     (*frf.mag_hi)[i]);
    }
    text += '\n';
  }
  write_file_atomic(path, text);
}

}  // namespace rig::io
