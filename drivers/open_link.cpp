#include "drivers/open_link.hpp"

#include "drivers/can/can_link.hpp"
#include "drivers/modbus/modbus_link.hpp"

namespace drivers {

LinkResult<std::unique_ptr<GovernorLink>> open_link(const LinkUri& uri,
                                                    const LinkOptions& options) {
  if (options.response_timeout.count() <= 0) {
    return LinkError{LinkErrorKind::kConfig, uri.text, "response timeout must be positive"};
  }
  if (uri.is_modbus()) return make_modbus_link(uri, options);
  return make_can_link(uri, options);
}

LinkResult<std::unique_ptr<GovernorLink>> open_link(const std::string& uri,
                                                    const LinkOptions& options) {
  auto parsed = parse_link_uri(uri);
  if (!parsed) return parsed.error();
  return open_link(parsed.value(), options);
}

}  // namespace drivers
