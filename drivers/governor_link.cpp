#include "drivers/governor_link.hpp"

namespace drivers {

const char* to_string(LinkErrorKind kind) {
  switch (kind) {
    case LinkErrorKind::kTimeout:
      return "timeout";
    case LinkErrorKind::kModbusException:
      return "modbus exception";
    case LinkErrorKind::kStale:
      return "stale sample";
    case LinkErrorKind::kChecksum:
      return "checksum/counter error";
    case LinkErrorKind::kLinkLost:
      return "link lost";
    case LinkErrorKind::kProtocol:
      return "protocol error";
    case LinkErrorKind::kUnavailable:
      return "unavailable";
    case LinkErrorKind::kConfig:
      return "configuration error";
  }
  return "unknown link error";
}

LinkResult<double> GovernorLink::read_held_bias() {
  return LinkError{LinkErrorKind::kUnavailable, uri(), "this link cannot read back the held bias"};
}

std::string LinkError::message() const {
  std::string text = to_string(kind);
  if (!where.empty()) text += " at " + where;
  if (!detail.empty()) text += ": " + detail;
  return text;
}

}  // namespace drivers
