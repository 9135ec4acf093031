// Helpers for report.json (DESIGN.md section 4: machine-readable, documented keys).
// JSON has no NaN or infinity: non-finite numbers are written as null.
#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace rig::report {

nlohmann::json number_or_null(double value);
nlohmann::json to_json_array(std::span<const double> values);
nlohmann::json to_json_array(const Eigen::VectorXd& values);
nlohmann::json to_json_matrix(const Eigen::MatrixXd& values);  // array of rows

std::vector<double> to_std_vector(const Eigen::VectorXd& values);

// Pretty-printed (2 spaces), written atomically; InputError when the folder is not writable.
void write_json_file(const std::filesystem::path& path, const nlohmann::json& doc);

}  // namespace rig::report
