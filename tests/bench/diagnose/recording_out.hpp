// Output shared by the concealed-effect programs and tests of `rig diagnose`: the recording
// files a generator writes, and the ranked hypotheses a benchmark prints.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>

#include "rig/diagnose/diagnose.hpp"

namespace rig::diagnose::bench {

// DIR/rec.csv (t,u,y; u in %, y in kW) and its sidecar DIR/rec.json (sample rate, units, seed,
// and the AC coupling of y when output_rc_s is set); DIR/model.json when `model` is given.
void write_diagnose_recording(const std::filesystem::path& dir, const Eigen::VectorXd& u,
                              const Eigen::VectorXd& y, double dt_s, std::uint64_t seed,
                              std::optional<double> output_rc_s,
                              const model::TransferFunction* model);

// The explanation and the four best hypotheses with their parameters and fits.
void print_hypotheses(const DiagnoseResult& result);

}  // namespace rig::diagnose::bench
