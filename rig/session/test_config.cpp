#include "rig/session/test_config.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <vector>

namespace rig::session {
namespace {

// Where a key sits in the document, for the one-line error.
std::string at_line(const toml::node& node) {
  const auto& begin = node.source().begin;
  return begin.line > 0 ? fmt::format(" (line {})", begin.line) : std::string{};
}

const char* type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    default:
      return "a date/time";
  }
}

struct Reader {
  const std::string& source;

  [[noreturn]] void fail(const toml::node& node, const std::string& key,
                         const std::string& what) const {
    throw ConfigError(fmt::format("{}: {}: {}{}", source, key, what, at_line(node)));
  }
  [[noreturn]] void wrong_type(const toml::node& node, const std::string& key,
                               const char* expected) const {
    fail(node, key, fmt::format("expected {}, got {}", expected, type_name(node)));
  }
  double number(const toml::node& node, const std::string& key) const {
    if (node.is_integer()) return static_cast<double>(node.as_integer()->get());
    if (node.is_floating_point()) return node.as_floating_point()->get();
    wrong_type(node, key, "a number");
  }
  long long integer(const toml::node& node, const std::string& key) const {
    if (!node.is_integer()) wrong_type(node, key, "an integer");
    return node.as_integer()->get();
  }
  bool boolean(const toml::node& node, const std::string& key) const {
    if (!node.is_boolean()) wrong_type(node, key, "a boolean (true/false)");
    return node.as_boolean()->get();
  }
  std::string string(const toml::node& node, const std::string& key) const {
    if (!node.is_string()) wrong_type(node, key, "a string");
    return node.as_string()->get();
  }
};

using Binder = std::function<void(const Reader&, const toml::node&, const std::string&)>;
using Section = std::map<std::string, Binder>;

Binder num(double& field) {
  return [&field](const Reader& r, const toml::node& n, const std::string& k) {
    field = r.number(n, k);
  };
}
Binder whole(int& field) {
  return [&field](const Reader& r, const toml::node& n, const std::string& k) {
    field = static_cast<int>(r.integer(n, k));
  };
}
Binder flag(bool& field) {
  return [&field](const Reader& r, const toml::node& n, const std::string& k) {
    field = r.boolean(n, k);
  };
}
Binder text(std::string& field) {
  return [&field](const Reader& r, const toml::node& n, const std::string& k) {
    field = r.string(n, k);
  };
}

Binder excitation_type(ExcitationType& field) {
  return [&field](const Reader& r, const toml::node& n, const std::string& k) {
    const std::string v = r.string(n, k);
    if (v == "gaussian") {
      field = ExcitationType::kGaussian;
    } else if (v == "prbs") {
      field = ExcitationType::kPrbs;
    } else if (v == "shaped") {
      field = ExcitationType::kShaped;
    } else {
      r.fail(n, k, fmt::format("expected \"gaussian\", \"prbs\" or \"shaped\", got \"{}\"", v));
    }
  };
}

Binder choice(std::string& field, std::vector<std::string> allowed) {
  return [&field, allowed](const Reader& r, const toml::node& n, const std::string& k) {
    const std::string v = r.string(n, k);
    std::string list;
    for (const auto& a : allowed) {
      if (a == v) {
        field = v;
        return;
      }
      list += (list.empty() ? "\"" : ", \"") + a + "\"";
    }
    r.fail(n, k, fmt::format("expected one of {}, got \"{}\"", list, v));
  };
}

// delay_s = "auto" or a number of seconds.
Binder delay(std::optional<double>& field) {
  return [&field](const Reader& r, const toml::node& n, const std::string& k) {
    if (n.is_string()) {
      if (n.as_string()->get() != "auto") r.fail(n, k, "expected \"auto\" or seconds");
      field.reset();
    } else {
      field = r.number(n, k);
    }
  };
}

std::map<std::string, Section> schema(TestConfig& c) {
  std::map<std::string, Section> s;
  s["link"] = {{"uri", text(c.link.uri)},
               {"sample_rate_hz", num(c.link.sample_rate_hz)},
               {"lockstep_ticks", whole(c.link.lockstep_ticks)},
               {"timeout_s", num(c.link.timeout_s)}};
  s["plant"] = {{"rated_power_kw", num(c.plant.rated_power_kw)}, {"preset", text(c.plant.preset)}};
  s["safety"] = {{"band_pct", num(c.safety.band_pct)},
                 {"allow_band_above_3pct", flag(c.safety.allow_band_above_3pct)},
                 {"plan_fraction", num(c.safety.plan_fraction)},
                 {"backoff_fraction", num(c.safety.backoff_fraction)},
                 {"clamp_pct", num(c.safety.clamp_pct)},
                 {"ramp_pct_per_s", num(c.safety.ramp_pct_per_s)},
                 {"activation_timeout_s", num(c.safety.activation_timeout_s)},
                 {"echo_tolerance_pct", num(c.safety.echo_tolerance_pct)},
                 {"echo_delay_s", num(c.safety.echo_delay_s)},
                 {"echo_max_bad_s", num(c.safety.echo_max_bad_s)}};
  s["steady_state"] = {{"duration_s", num(c.steady_state.duration_s)},
                       {"max_noise_pct", num(c.steady_state.max_noise_pct)},
                       {"max_drift_pct", num(c.steady_state.max_drift_pct)},
                       {"min_power_kw", num(c.steady_state.min_power_kw)}};
  s["pilot"] = {{"amplitude_pct", num(c.pilot.amplitude_pct)},
                {"duration_s", num(c.pilot.duration_s)}};
  s["excitation"] = {{"type", excitation_type(c.excitation.type)},
                     {"bandwidth_hz", num(c.excitation.bandwidth_hz)},
                     {"seed",
                      [&c](const Reader& r, const toml::node& n, const std::string& k) {
                        const long long v = r.integer(n, k);
                        if (v < 0) r.fail(n, k, "expected a non-negative integer");
                        c.excitation.seed = static_cast<std::uint64_t>(v);
                      }},
                     {"ac_coupling_rc_s", num(c.excitation.ac_coupling_rc_s)},
                     {"prbs_register_length", whole(c.excitation.prbs_register_length)},
                     {"prbs_clock_divider", whole(c.excitation.prbs_clock_divider)}};
  s["mmfm"] = {{"order_n", whole(c.mmfm.order_n)},
               {"order_m", whole(c.mmfm.order_m)},
               {"delay_s", delay(c.mmfm.delay_s)},
               {"lags", whole(c.mmfm.lags)},
               {"block_size", whole(c.mmfm.block_size)},
               {"skip", whole(c.mmfm.skip)},
               {"correlator", choice(c.mmfm.correlator, {"direct", "fft", "relay", "polarity"})},
               {"averaging", choice(c.mmfm.averaging, {"cumulative", "exponential"})},
               {"averaging_w", whole(c.mmfm.averaging_w)},
               {"auto_order", flag(c.mmfm.auto_order)},
               {"target_db", num(c.mmfm.target_db)},
               {"target_deg", num(c.mmfm.target_deg)},
               {"target_rel_std_error",
                [](const Reader& r, const toml::node& n, const std::string& k) {
                  r.fail(n, k,
                         "replaced by mmfm.target_db and mmfm.target_deg (the stopping "
                         "rule is the model's 95 % band over the compare band)");
                }},
               {"min_duration_s", num(c.mmfm.min_duration_s)},
               {"max_duration_s", num(c.mmfm.max_duration_s)},
               {"min_applied_fraction", num(c.mmfm.min_applied_fraction)}};
  s["sweep"] = {{"enabled", flag(c.sweep.enabled)},
                {"from_hz", num(c.sweep.from_hz)},
                {"to_hz", num(c.sweep.to_hz)},
                {"points", whole(c.sweep.points)},
                {"settle_cycles", num(c.sweep.settle_cycles)},
                {"integrate_cycles", num(c.sweep.integrate_cycles)},
                {"settle_time_constants", num(c.sweep.settle_time_constants)},
                {"min_integrate_s", num(c.sweep.min_integrate_s)}};
  s["compare"] = {{"from_hz", num(c.compare.from_hz)},
                  {"to_hz", num(c.compare.to_hz)},
                  {"mag_tol_db", num(c.compare.mag_tol_db)},
                  {"phase_tol_deg", num(c.compare.phase_tol_deg)},
                  {"min_coherence", num(c.compare.min_coherence)}};
  s["output"] = {{"flush_interval_s", num(c.output.flush_interval_s)},
                 {"live_interval_s", num(c.output.live_interval_s)}};
  return s;
}

void bind_document(const toml::table& doc, TestConfig& config) {
  const Reader reader{config.source};
  auto sections = schema(config);
  for (auto&& [section_key, section_node] : doc) {
    const std::string name(section_key.str());
    auto section = sections.find(name);
    if (section == sections.end()) {
      reader.fail(section_node, name, "unknown section or key");
    }
    const toml::table* table = section_node.as_table();
    if (table == nullptr) reader.wrong_type(section_node, name, "a table");
    for (auto&& [key, node] : *table) {
      const std::string path = name + "." + std::string(key.str());
      auto binder = section->second.find(std::string(key.str()));
      if (binder == section->second.end()) reader.fail(node, path, "unknown key");
      binder->second(reader, node, path);
    }
  }
}

}  // namespace

const char* to_string(ExcitationType type) {
  switch (type) {
    case ExcitationType::kPrbs:
      return "prbs";
    case ExcitationType::kShaped:
      return "shaped";
    case ExcitationType::kGaussian:
      break;
  }
  return "gaussian";
}

TestConfig parse_test_toml(const std::string& text, const std::string& source) {
  TestConfig config;
  config.source = source;
  toml::table doc;
  try {
    doc = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw ConfigError(fmt::format("{}: {} (line {}, column {})", source, e.description(),
                                  e.source().begin.line, e.source().begin.column));
  }
  bind_document(doc, config);
  validate(config);
  return config;
}

TestConfig load_test_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(fmt::format("{}: cannot open the test file", path.string()));
  std::ostringstream text;
  text << in.rdbuf();
  return parse_test_toml(text.str(), path.string());
}

}  // namespace rig::session
