#include "rig/io/sidecar.hpp"

#include <cmath>

#include "rig/io/atomic_file.hpp"
#include "rig/io/input_error.hpp"

namespace rig::io {
namespace {

using nlohmann::json;

double positive_number(const json& doc, const char* key, const std::string& source) {
  const json& v = doc.at(key);
  if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() <= 0.0) {
    throw InputError(
        source, 0, "",
        std::string("key \"") + key + "\": expected a finite number > 0, found " + v.dump());
  }
  return v.get<double>();
}

std::string text(const json& doc, const char* key, const std::string& source) {
  const json& v = doc.at(key);
  if (!v.is_string()) {
    throw InputError(source, 0, "",
                     std::string("key \"") + key + "\": expected a string, found " + v.dump());
  }
  return v.get<std::string>();
}

void read_units(const json& doc, const std::string& source, Sidecar& out) {
  const json& v = doc.at("units");
  if (!v.is_object()) {
    throw InputError(source, 0, "", "key \"units\": expected an object {column: unit}");
  }
  for (const auto& [column, unit] : v.items()) {
    if (!unit.is_string()) {
      throw InputError(
          source, 0, "",
          "key \"units\": unit of \"" + column + "\" must be a string, found " + unit.dump());
    }
    out.units[column] = unit.get<std::string>();
  }
}

void read_coupled(const json& doc, const std::string& source, Sidecar& out) {
  const json& v = doc.at("coupled_columns");
  if (!v.is_array()) {
    throw InputError(source, 0, "", "key \"coupled_columns\": expected an array of names");
  }
  for (const json& name : v) {
    if (!name.is_string()) {
      throw InputError(source, 0, "",
                       "key \"coupled_columns\": expected strings, found " + name.dump());
    }
    out.coupled_columns.push_back(name.get<std::string>());
  }
}

}  // namespace

std::filesystem::path sidecar_path(const std::filesystem::path& recording) {
  std::filesystem::path p = recording;
  p.replace_extension(".json");
  return p;
}

Sidecar parse_sidecar(const json& doc, const std::string& source) {
  if (!doc.is_object()) {
    throw InputError(source, 0, "", "expected a JSON object");
  }
  Sidecar out;
  out.present = true;
  out.source = source;
  out.raw = doc;
  if (doc.contains("sample_rate_hz"))
    out.sample_rate_hz = positive_number(doc, "sample_rate_hz", source);
  if (doc.contains("coupling_rc_s"))
    out.coupling_rc_s = positive_number(doc, "coupling_rc_s", source);
  if (doc.contains("y_sampled_after_s")) {
    const json& v = doc.at("y_sampled_after_s");
    if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0.0) {
      throw InputError(source, 0, "",
                       "key \"y_sampled_after_s\": expected a time >= 0 in s, found " + v.dump());
    }
    out.y_sampled_after_s = v.get<double>();
  }
  if (doc.contains("units")) read_units(doc, source, out);
  if (doc.contains("coupled_columns")) read_coupled(doc, source, out);
  if (doc.contains("link")) out.link = text(doc, "link", source);
  if (doc.contains("preset")) out.preset = text(doc, "preset", source);
  if (doc.contains("operating_point")) {
    if (!doc["operating_point"].is_object()) {
      throw InputError(source, 0, "", "key \"operating_point\": expected an object");
    }
    out.operating_point = doc["operating_point"];
  }
  if (doc.contains("seed")) {
    if (!doc["seed"].is_number_unsigned()) {
      throw InputError(source, 0, "",
                       "key \"seed\": expected an unsigned integer, found " + doc["seed"].dump());
    }
    out.seed = doc["seed"].get<std::uint64_t>();
  }
  return out;
}

Sidecar read_sidecar(const std::filesystem::path& path) {
  const std::string text = read_small_input_file(path, "a sidecar", kMaxSidecarBytes);
  json doc = json::parse(text, nullptr, /*allow_exceptions=*/false);  // skips a UTF-8 BOM
  if (doc.is_discarded()) {
    throw InputError(path.string(), 0, "", "expected valid JSON (parse error)");
  }
  return parse_sidecar(doc, path.string());
}

json to_json(const Sidecar& sidecar) {
  json doc = sidecar.raw.is_object() ? sidecar.raw : json::object();
  if (sidecar.sample_rate_hz) doc["sample_rate_hz"] = *sidecar.sample_rate_hz;
  if (!sidecar.units.empty()) doc["units"] = sidecar.units;
  if (!sidecar.operating_point.empty()) doc["operating_point"] = sidecar.operating_point;
  if (sidecar.coupling_rc_s) doc["coupling_rc_s"] = *sidecar.coupling_rc_s;
  if (!sidecar.coupled_columns.empty()) doc["coupled_columns"] = sidecar.coupled_columns;
  if (!sidecar.link.empty()) doc["link"] = sidecar.link;
  if (!sidecar.preset.empty()) doc["preset"] = sidecar.preset;
  if (sidecar.seed) doc["seed"] = *sidecar.seed;
  if (sidecar.y_sampled_after_s) doc["y_sampled_after_s"] = *sidecar.y_sampled_after_s;
  return doc;
}

void write_sidecar(const std::filesystem::path& path, const Sidecar& sidecar) {
  write_file_atomic(path, to_json(sidecar).dump(2) + "\n");
}

}  // namespace rig::io
