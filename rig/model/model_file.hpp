// Model JSON (DESIGN.md section 5):
//   {"type":"tf", "num":[b_m..b_0], "den":[a_n..a_0], "delay_s":Td,
//    "cov":[[..],..], "fit_percent":x, "input":"u", "output":"y", "units":{..} or "..."}
// Coefficients highest power first (scipy / MATLAB). Validation on read and write: type
// "tf", den non-empty with a non-zero leading coefficient, num non-empty, proper
// (deg num <= deg den after trimming num's leading zeros), every number finite,
// delay_s >= 0, cov square.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "rig/model/transfer_function.hpp"

namespace rig::model {

struct ModelFile {
  TransferFunction tf;
  std::optional<Eigen::MatrixXd> cov;  // parameter covariance (order as the producer says)
  std::optional<double> fit_percent;
  std::string input;  // column/signal names, "" when unknown
  std::string output;
  nlohmann::json units;                             // null, a string ("kW/%") or an object
  nlohmann::json extra = nlohmann::json::object();  // other keys, kept on round trip
};

// InputError naming `source` and the key on any violation.
ModelFile model_from_json(const nlohmann::json& doc, const std::string& source);
nlohmann::json model_to_json(const ModelFile& model);

ModelFile read_model(const std::filesystem::path& path);
// Validates first (std::invalid_argument on a bad model), then writes atomically.
void write_model(const std::filesystem::path& path, const ModelFile& model);

}  // namespace rig::model
