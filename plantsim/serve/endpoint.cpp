#include "plantsim/serve/endpoint.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <map>

#include "plantsim/plant/plant.hpp"

namespace plantsim::serve {
namespace {

drivers::LinkUri parse_endpoint(const std::string& text, const char* option, const char* family,
                                const char* expected) {
  auto uri = drivers::parse_link_uri(text, family);
  if (!uri) {
    throw ConfigError(fmt::format("{} {}: {}", option, uri.error().where, uri.error().detail));
  }
  const bool modbus = std::string(family) == "modbus";
  if (uri->is_modbus() != modbus) {
    throw ConfigError(fmt::format("{} '{}': expected {}", option, text, expected));
  }
  return uri.value();
}

}  // namespace

drivers::LinkUri parse_modbus_endpoint(const std::string& text) {
  auto uri = parse_endpoint(text, "--modbus", "modbus", "tcp://HOST:PORT or rtu:DEVICE?baud=N");
  if (uri.scheme == drivers::LinkScheme::kModbusRtu && (uri.unit < 1 || uri.unit > 247)) {
    throw ConfigError(fmt::format("--modbus '{}': expected unit 1..247 for an RTU slave", text));
  }
  return uri;
}

drivers::LinkUri parse_can_endpoint(const std::string& text) {
  return parse_endpoint(text, "--can", "can", "udp://HOST:PORT or socketcan:IFACE");
}

std::chrono::nanoseconds parse_tick(const std::string& text) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  const std::string unit(end, text.data() + text.size());
  static const std::map<std::string, double> kNsPer = {
      {"ns", 1.0}, {"us", 1e3}, {"ms", 1e6}, {"s", 1e9}};
  const auto it = kNsPer.find(unit);
  if (ec != std::errc{} || it == kNsPer.end() || !std::isfinite(value)) {
    throw ConfigError(
        fmt::format("--tick '{}': expected a duration like 1ms, 500us, 0.002s", text));
  }
  const double ns = value * it->second;
  if (ns < 1e5 || ns > 1e9) {
    throw ConfigError(fmt::format("--tick '{}': expected 100us .. 1s", text));
  }
  return std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(ns)));
}

}  // namespace plantsim::serve
