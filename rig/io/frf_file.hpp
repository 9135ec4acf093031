// Frequency-response CSV (DESIGN.md section 5):
//   freq_hz,mag,phase_deg,coherence[,mag_lo,mag_hi]
// mag is |H| (linear, not dB), phase in degrees, coherence in [0, 1]; mag_lo/mag_hi bound
// |H| (e.g. a 95 % interval) when known. Frequencies strictly increasing and > 0.
#pragma once

#include <filesystem>
#include <optional>

#include <Eigen/Core>

namespace rig::io {

struct Frf {
  Eigen::VectorXd freq_hz;
  Eigen::VectorXd mag;
  Eigen::VectorXd phase_deg;
  Eigen::VectorXd coherence;
  std::optional<Eigen::VectorXd> mag_lo;  // both or neither
  std::optional<Eigen::VectorXd> mag_hi;

  Eigen::Index size() const { return freq_hz.size(); }
};

// InputError (file, line, column, what was expected) on any defect.
Frf read_frf(const std::filesystem::path& path);
// std::invalid_argument when the columns differ in length or break the rules above.
void write_frf(const std::filesystem::path& path, const Frf& frf);

}  // namespace rig::io
