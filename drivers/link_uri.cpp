#include "drivers/link_uri.hpp"

#include <charconv>
#include <optional>

namespace drivers {
namespace {

LinkError uri_error(std::string_view uri, std::string_view part, std::string detail) {
  return LinkError{LinkErrorKind::kConfig, "URI '" + std::string(uri) + "' " + std::string(part),
                   std::move(detail)};
}

std::optional<int> parse_int(std::string_view text, int lo, int hi) {
  int value = 0;
  const auto* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc{} || ptr != end || value < lo || value > hi) {
    return std::nullopt;
  }
  return value;
}

// "host:port" of the tcp/udp forms; `rest` is what follows "//".
LinkResult<void> parse_host_port(std::string_view uri, std::string_view rest, LinkUri& out) {
  const auto colon = rest.rfind(':');
  if (colon == std::string_view::npos) {
    return uri_error(uri, "authority",
                     "expected host:port after '//', got '" + std::string(rest) + "'");
  }
  out.host = std::string(rest.substr(0, colon));
  if (out.host.empty()) return uri_error(uri, "host", "expected a host name or address");
  const auto port = parse_int(rest.substr(colon + 1), 0, 65535);
  if (!port) {
    return uri_error(
        uri, "port",
        "expected an integer 0..65535, got '" + std::string(rest.substr(colon + 1)) + "'");
  }
  out.port = *port;
  return {};
}

LinkResult<void> apply_query_item(std::string_view uri, std::string_view item, LinkUri& out) {
  const auto eq = item.find('=');
  const std::string key(item.substr(0, eq));
  const std::string_view value = eq == std::string_view::npos ? "" : item.substr(eq + 1);
  const std::string part = "query '" + std::string(item) + "'";
  auto number = [&](int lo, int hi, int& field, const char* what) -> LinkResult<void> {
    const auto v = parse_int(value, lo, hi);
    if (!v) return uri_error(uri, part, std::string("expected ") + what);
    field = *v;
    return {};
  };
  const bool rtu = out.scheme == LinkScheme::kModbusRtu;
  if (key == "unit" && out.is_modbus()) return number(0, 247, out.unit, "a unit id 0..247");
  if (key == "baud" && rtu) return number(1, 4000000, out.baud, "a positive baud rate");
  if (key == "data" && rtu) return number(5, 8, out.data_bits, "data bits 5..8");
  if (key == "stop" && rtu) return number(1, 2, out.stop_bits, "stop bits 1 or 2");
  if (key == "command" && out.is_can()) {
    if (value != "ff50" && value != "tsc1") return uri_error(uri, part, "expected ff50 or tsc1");
    out.can_command = value == "tsc1" ? CanCommand::kTsc1 : CanCommand::kBiasFrame;
    return {};
  }
  if (key == "sync_rpm" && out.is_can()) {
    const auto* end = value.data() + value.size();
    auto [ptr, ec] = std::from_chars(value.data(), end, out.sync_rpm);
    if (value.empty() || ec != std::errc{} || ptr != end || !(out.sync_rpm > 0.0)) {
      return uri_error(uri, part, "expected a positive speed in rpm");
    }
    return {};
  }
  if (key == "parity" && rtu) {
    if (value.size() != 1 || (value[0] != 'N' && value[0] != 'E' && value[0] != 'O')) {
      return uri_error(uri, part, "expected parity N, E or O");
    }
    out.parity = value[0];
    return {};
  }
  return uri_error(uri, part,
                   std::string("unknown key for ") + to_string(out.scheme) +
                       (rtu               ? " (expected unit, baud, parity, data, stop)"
                        : out.is_modbus() ? " (expected unit)"
                                          : " (expected command, sync_rpm)"));
}

LinkResult<void> parse_query(std::string_view uri, std::string_view query, LinkUri& out) {
  while (!query.empty()) {
    const auto amp = query.find('&');
    const auto item = query.substr(0, amp);
    if (!item.empty()) {
      if (auto r = apply_query_item(uri, item, out); !r) return r;
    }
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {};
}

}  // namespace

bool LinkUri::is_modbus() const {
  return scheme == LinkScheme::kModbusTcp || scheme == LinkScheme::kModbusRtu;
}
bool LinkUri::is_can() const { return !is_modbus(); }

const char* to_string(LinkScheme scheme) {
  switch (scheme) {
    case LinkScheme::kModbusTcp:
      return "modbus+tcp";
    case LinkScheme::kModbusRtu:
      return "modbus+rtu";
    case LinkScheme::kCanSocketcan:
      return "can+socketcan";
    case LinkScheme::kCanUdp:
      return "can+udp";
  }
  return "?";
}

LinkResult<LinkUri> parse_link_uri(std::string_view uri_in, std::string_view default_family) {
  std::string text(uri_in);
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    return uri_error(text, "scheme",
                     "expected '<scheme>:' (modbus+tcp, modbus+rtu, "
                     "can+socketcan, can+udp)");
  }
  if (text.substr(0, colon).find('+') == std::string::npos && !default_family.empty()) {
    text = std::string(default_family) + "+" + text;
  }
  LinkUri out;
  out.text = text;
  const std::string_view uri = out.text;
  const auto scheme_end = uri.find(':');
  const std::string_view scheme = uri.substr(0, scheme_end);
  std::string_view rest = uri.substr(scheme_end + 1);
  std::string_view query;
  if (const auto q = rest.find('?'); q != std::string_view::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  const bool slashes = rest.substr(0, 2) == "//";
  if (scheme == "modbus+tcp" || scheme == "can+udp") {
    out.scheme = scheme == "can+udp" ? LinkScheme::kCanUdp : LinkScheme::kModbusTcp;
    if (!slashes) return uri_error(uri, "authority", "expected '//host:port' after the scheme");
    if (auto r = parse_host_port(uri, rest.substr(2), out); !r) return r.error();
  } else if (scheme == "modbus+rtu" || scheme == "can+socketcan") {
    out.scheme = scheme == "can+socketcan" ? LinkScheme::kCanSocketcan : LinkScheme::kModbusRtu;
    if (slashes) rest.remove_prefix(2);  // tolerate modbus+rtu:///dev/ttyUSB0
    out.device = std::string(rest);
    if (out.device.empty()) {
      return uri_error(uri, "device",
                       out.scheme == LinkScheme::kModbusRtu
                           ? "expected a serial device, e.g. /dev/ttyUSB0"
                           : "expected a CAN interface name, e.g. can0");
    }
  } else {
    return uri_error(uri, "scheme",
                     "expected modbus+tcp, modbus+rtu, can+socketcan or "
                     "can+udp, got '" +
                         std::string(scheme) + "'");
  }
  if (auto r = parse_query(uri, query, out); !r) return r.error();
  if (out.can_command == CanCommand::kTsc1 && out.sync_rpm <= 0.0) {
    return uri_error(uri, "query", "expected sync_rpm=<rpm> with command=tsc1");
  }
  return out;
}

}  // namespace drivers
