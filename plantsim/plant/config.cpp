#include "plantsim/plant/config.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>

namespace plantsim {
namespace {

double parse_number(std::string_view s, bool* ok) {
  double v = 0.0;
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, v);
  *ok = ec == std::errc() && ptr == end && !s.empty();
  return v;
}

void apply_table(const toml::table& table, const std::string& block, const std::string& origin,
                 Params* params) {
  for (auto&& [key, node] : table) {
    const std::string name = block + "." + std::string(key.str());
    const std::string where = fmt::format("{}:{}", origin, node.source().begin.line);
    const auto id = find_param(name);
    if (!id || name.find('.') != name.rfind('.')) {
      throw ConfigError(fmt::format(
          "{}: unknown parameter '{}' (plantsim --list-params shows them all)", where, name));
    }
    double value = 0.0;
    if (node.is_boolean()) {
      value = node.value<bool>().value_or(false) ? 1.0 : 0.0;
    } else if (node.is_number()) {
      value = node.value<double>().value_or(0.0);
    } else {
      throw ConfigError(fmt::format("{}: {} must be a number in {}", where, name, spec(*id).unit));
    }
    params->set(*id, value, where);
  }
}

}  // namespace

Params parse_toml(const std::string& text, const std::string& origin) {
  toml::table root;
  try {
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw ConfigError(
        fmt::format("{}:{}: malformed TOML: {}", origin, e.source().begin.line, e.description()));
  }
  Params params;
  if (const auto* base = root.get("preset")) {
    const auto name = base->value<std::string>();
    if (!name) {
      throw ConfigError(fmt::format("{}:{}: preset must be a string naming a preset", origin,
                                    base->source().begin.line));
    }
    params = preset(*name);
  }
  for (auto&& [key, node] : root) {
    if (key.str() == "preset") continue;
    const auto* table = node.as_table();
    if (table == nullptr) {
      throw ConfigError(
          fmt::format("{}:{}: '{}' must be a table of parameters ([gov], [engine], ...)", origin,
                      node.source().begin.line, key.str()));
    }
    apply_table(*table, std::string(key.str()), origin, &params);
  }
  return params;
}

Params load_toml(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError(fmt::format("{}: cannot open plant TOML", file.string()));
  std::stringstream text;
  text << in.rdbuf();
  return parse_toml(text.str(), file.string());
}

TimedChange parse_change(const std::string& text) {
  constexpr const char* kSyntax = "NAME=VALUE@t=SECONDS[,ramp=SECONDS], e.g. injector_3=0@t=20";
  const auto eq = text.find('=');
  const auto at = text.find("@t=");
  if (eq == std::string::npos || at == std::string::npos || at < eq) {
    throw ConfigError(fmt::format("--fault '{}': expected {}", text, kSyntax));
  }
  const std::string name = text.substr(0, eq);
  const auto id = find_param(name);
  if (!id) {
    throw ConfigError(fmt::format(
        "--fault '{}': unknown parameter '{}' (write block.name when a bare name is ambiguous)",
        text, name));
  }
  const std::string_view view(text);
  const auto comma = text.find(',', at);
  const auto time_end = comma == std::string::npos ? text.size() : comma;
  bool ok_value = false;
  bool ok_time = false;
  const double value = parse_number(view.substr(eq + 1, at - eq - 1), &ok_value);
  const double time_s = parse_number(view.substr(at + 3, time_end - at - 3), &ok_time);
  if (!ok_value) throw ConfigError(fmt::format("--fault '{}': VALUE is not a number", text));
  if (!ok_time || time_s < 0.0) {
    throw ConfigError(fmt::format("--fault '{}': SECONDS must be a number >= 0", text));
  }
  double ramp_s = 0.0;
  if (comma != std::string::npos) {
    constexpr std::string_view kRamp = ",ramp=";
    bool ok_ramp = view.substr(comma, kRamp.size()) == kRamp;
    if (ok_ramp) ramp_s = parse_number(view.substr(comma + kRamp.size()), &ok_ramp);
    if (!ok_ramp || !(ramp_s >= 0.0 && ramp_s <= 1e7)) {
      throw ConfigError(fmt::format(
          "--fault '{}': expected ',ramp=SECONDS' after the time, SECONDS a number 0 .. 1e7",
          text));
    }
    if (ramp_s > 0.0 && !rampable(*id)) {
      throw ConfigError(fmt::format("--fault '{}': {} takes abrupt changes only (no ramp)", text,
                                    spec(*id).name));
    }
  }
  Params probe;  // range check with the same message as the TOML path
  probe.set(*id, value, fmt::format("--fault '{}'", text));
  return TimedChange{*id, value, time_s, ramp_s, text};
}

ResolvedConfig resolve(const PlantOptions& options) {
  ResolvedConfig out;
  out.params = options.config ? load_toml(*options.config) : preset(options.preset);
  for (const auto& f : options.faults) out.changes.push_back(parse_change(f));
  std::stable_sort(out.changes.begin(), out.changes.end(),
                   [](const TimedChange& a, const TimedChange& b) { return a.time_s < b.time_s; });
  return out;
}

}  // namespace plantsim
