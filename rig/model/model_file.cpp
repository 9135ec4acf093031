#include "rig/model/model_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rig/model/atomic_file.hpp"
#include "rig/model/input_error.hpp"

namespace rig::model {
namespace {

using nlohmann::json;

Eigen::VectorXd coefficients(const json& doc, const char* key, const std::string& source) {
  if (!doc.contains(key)) throw InputError(source, 0, "", fmt::format("missing key \"{}\"", key));
  const json& v = doc.at(key);
  if (!v.is_array() || v.empty()) {
    throw InputError(source, 0, "",
                     fmt::format("key \"{}\": expected a non-empty array of "
                                 "numbers, found {}",
                                 key, v.dump()));
  }
  Eigen::VectorXd out(Eigen::Index(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) {
      throw InputError(source, 0, "",
                       fmt::format("key \"{}\"[{}]: expected a finite number, "
                                   "found {}",
                                   key, i, v[i].dump()));
    }
    out[Eigen::Index(i)] = v[i].get<double>();
  }
  return out;
}

Eigen::MatrixXd covariance(const json& v, const std::string& source) {
  const std::size_t n = v.is_array() ? v.size() : 0;
  if (n == 0) throw InputError(source, 0, "", "key \"cov\": expected a square array of arrays");
  const auto size = static_cast<Eigen::Index>(n);
  Eigen::MatrixXd out(size, size);
  for (std::size_t i = 0; i < n; ++i) {
    if (!v[i].is_array() || v[i].size() != n) {
      throw InputError(source, 0, "",
                       fmt::format("key \"cov\": row {} must hold {} numbers", i, n));
    }
    for (std::size_t j = 0; j < n; ++j) {
      if (!v[i][j].is_number() || !std::isfinite(v[i][j].get<double>())) {
        throw InputError(source, 0, "",
                         fmt::format("key \"cov\"[{}][{}]: expected a finite "
                                     "number, found {}",
                                     i, j, v[i][j].dump()));
      }
      out(Eigen::Index(i), Eigen::Index(j)) = v[i][j].get<double>();
    }
  }
  return out;
}

// deg num <= deg den, den's leading coefficient non-zero; returns "" when valid.
std::string structure_problem(const TransferFunction& tf) {
  if (tf.den.size() == 0) return "key \"den\": expected a non-empty array";
  if (tf.num.size() == 0) return "key \"num\": expected a non-empty array";
  if (tf.den[0] == 0.0) return "key \"den\": the leading (highest-power) coefficient is 0";
  if (!tf.den.allFinite() || !tf.num.allFinite()) return "coefficients must be finite";
  Eigen::Index lead = 0;
  while (lead + 1 < tf.num.size() && tf.num[lead] == 0.0) ++lead;
  if (tf.num.size() - lead > tf.den.size()) {
    return fmt::format("improper model: numerator order {} exceeds denominator order {}",
                       tf.num.size() - lead - 1, tf.den.size() - 1);
  }
  if (!std::isfinite(tf.delay_s) || tf.delay_s < 0.0) {
    return fmt::format("key \"delay_s\": expected a finite number >= 0, found {}", tf.delay_s);
  }
  return "";
}

std::vector<double> to_std(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

}  // namespace

ModelFile model_from_json(const json& doc, const std::string& source) {
  if (!doc.is_object()) throw InputError(source, 0, "", "expected a JSON object");
  if (!doc.contains("type") || doc["type"] != "tf") {
    throw InputError(source, 0, "", "key \"type\": expected \"tf\"");
  }
  ModelFile out;
  out.tf.num = coefficients(doc, "num", source);
  out.tf.den = coefficients(doc, "den", source);
  if (doc.contains("delay_s")) {
    if (!doc["delay_s"].is_number()) {
      throw InputError(source, 0, "", "key \"delay_s\": expected a number >= 0");
    }
    out.tf.delay_s = doc["delay_s"].get<double>();
  }
  if (const std::string problem = structure_problem(out.tf); !problem.empty()) {
    throw InputError(source, 0, "", problem);
  }
  if (doc.contains("cov") && !doc["cov"].is_null()) out.cov = covariance(doc["cov"], source);
  if (doc.contains("fit_percent") && !doc["fit_percent"].is_null()) {
    if (!doc["fit_percent"].is_number()) {
      throw InputError(source, 0, "", "key \"fit_percent\": expected a number");
    }
    out.fit_percent = doc["fit_percent"].get<double>();
  }
  for (const char* key : {"input", "output"}) {
    if (!doc.contains(key)) continue;
    if (!doc[key].is_string()) {
      throw InputError(source, 0, "", fmt::format("key \"{}\": expected a string", key));
    }
    (std::string(key) == "input" ? out.input : out.output) = doc[key].get<std::string>();
  }
  if (doc.contains("units")) out.units = doc["units"];
  for (const auto& [key, value] : doc.items()) {
    static const std::vector<std::string> known = {
        "type", "num", "den", "delay_s", "cov", "fit_percent", "input", "output", "units"};
    if (std::find(known.begin(), known.end(), key) == known.end()) out.extra[key] = value;
  }
  return out;
}

json model_to_json(const ModelFile& model) {
  if (const std::string problem = structure_problem(model.tf); !problem.empty()) {
    throw std::invalid_argument("model: " + problem);
  }
  json doc = model.extra.is_object() ? model.extra : json::object();
  doc["type"] = "tf";
  doc["num"] = to_std(model.tf.num);
  doc["den"] = to_std(model.tf.den);
  doc["delay_s"] = model.tf.delay_s;
  if (model.cov) {
    json rows = json::array();
    for (Eigen::Index i = 0; i < model.cov->rows(); ++i) {
      rows.push_back(to_std(model.cov->row(i).transpose()));
    }
    doc["cov"] = rows;
  }
  if (model.fit_percent) doc["fit_percent"] = *model.fit_percent;
  if (!model.input.empty()) doc["input"] = model.input;
  if (!model.output.empty()) doc["output"] = model.output;
  if (!model.units.is_null()) doc["units"] = model.units;
  return doc;
}

ModelFile read_model(const std::filesystem::path& path) {
  const std::string text = read_file_text(path);
  const json doc = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded())
    throw InputError(path.string(), 0, "", "expected valid JSON (parse error)");
  return model_from_json(doc, path.string());
}

void write_model(const std::filesystem::path& path, const ModelFile& model) {
  write_file_atomic(path, model_to_json(model).dump(2) + "\n");
}

}  // namespace rig::model
