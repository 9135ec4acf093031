#include "rig/report/json_out.hpp"

#include <cmath>

#include "rig/io/atomic_file.hpp"

namespace rig::report {

nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json to_json_array(std::span<const double> values) {
  nlohmann::json out = nlohmann::json::array();
  for (double v : values) out.push_back(number_or_null(v));
  return out;
}

nlohmann::json to_json_array(const Eigen::VectorXd& values) {
  return to_json_array(std::span<const double>(values.data(), std::size_t(values.size())));
}

nlohmann::json to_json_matrix(const Eigen::MatrixXd& values) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    const Eigen::VectorXd row = values.row(i).transpose();
    out.push_back(to_json_array(row));
  }
  return out;
}

std::vector<double> to_std_vector(const Eigen::VectorXd& values) {
  return {values.data(), values.data() + values.size()};
}

void write_json_file(const std::filesystem::path& path, const nlohmann::json& doc) {
  io::write_file_atomic(path, doc.dump(2) + "\n");
}

}  // namespace rig::report
