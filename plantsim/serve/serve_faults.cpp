#include "plantsim/serve/serve_faults.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "plantsim/plant/plant.hpp"

namespace plantsim::serve {
namespace {

constexpr const char* kPrefix = "serve.";
constexpr const char* kExpected =
    "expected serve.freeze_counter, serve.nan_power or serve.drop_link =0|1@t=SECONDS";

[[noreturn]] void fail(const std::string& text, const std::string& what) {
  throw ConfigError(fmt::format("--fault {}: {}", text, what));
}

// True when all of `s` is one finite number.
bool parse_number(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(out);
}

}  // namespace

const char* to_string(ServeFault fault) {
  switch (fault) {
    case ServeFault::kFreezeCounter:
      return "serve.freeze_counter";
    case ServeFault::kNanPower:
      return "serve.nan_power";
    case ServeFault::kDropLink:
      return "serve.drop_link";
  }
  return "serve.?";
}

bool is_serve_fault(const std::string& text) { return text.rfind(kPrefix, 0) == 0; }

ServeFaultChange parse_serve_fault(const std::string& text) {
  const auto eq = text.find('=');
  const auto at = text.find("@t=");
  if (eq == std::string::npos || at == std::string::npos || at < eq) {
    fail(text, std::string("malformed; ") + kExpected);
  }
  const std::string name = text.substr(0, eq);
  ServeFaultChange c;
  c.text = text;
  bool known = false;
  for (int i = 0; i < kServeFaultCount; ++i) {
    if (name == to_string(static_cast<ServeFault>(i))) {
      c.fault = static_cast<ServeFault>(i);
      known = true;
    }
  }
  if (!known) fail(text, fmt::format("unknown serve fault '{}'; {}", name, kExpected));
  const std::string value = text.substr(eq + 1, at - eq - 1);
  if (value != "0" && value != "1") fail(text, fmt::format("value '{}': expected 0 or 1", value));
  c.on = value == "1";
  double t_s = 0.0;
  if (!parse_number(text.substr(at + 3), t_s) || t_s < 0.0 || t_s > 1e7) {
    fail(text, "time: expected seconds of plant time >= 0");
  }
  c.time = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(t_s));
  return c;
}

std::vector<ServeFaultChange> split_serve_faults(std::vector<std::string>& faults) {
  std::vector<ServeFaultChange> serve;
  std::vector<std::string> plant;
  for (const auto& f : faults) {
    if (is_serve_fault(f)) {
      serve.push_back(parse_serve_fault(f));
    } else {
      plant.push_back(f);
    }
  }
  faults = std::move(plant);
  std::stable_sort(serve.begin(), serve.end(),
                   [](const auto& a, const auto& b) { return a.time < b.time; });
  return serve;
}

ServeFaultSchedule::ServeFaultSchedule(std::vector<ServeFaultChange> changes)
    : changes_(std::move(changes)) {
  std::stable_sort(changes_.begin(), changes_.end(),
                   [](const auto& a, const auto& b) { return a.time < b.time; });
}

bool ServeFaultSchedule::active(ServeFault fault, std::chrono::nanoseconds plant_time) const {
  bool on = false;
  for (const auto& c : changes_) {
    if (c.time > plant_time) break;
    if (c.fault == fault) on = c.on;
  }
  return on;
}

}  // namespace plantsim::serve
