// The link factory: URI -> GovernorLink (DESIGN.md section 6). The link comes back
// unconfigured; the caller runs the lifecycle configure/activate/cycle/deactivate/close.
#pragma once

#include <memory>
#include <string>

#include "drivers/governor_link.hpp"
#include "drivers/link_options.hpp"
#include "drivers/link_uri.hpp"

namespace drivers {

LinkResult<std::unique_ptr<GovernorLink>> open_link(const LinkUri& uri,
                                                    const LinkOptions& options = {});
// Parses the URI first; a bad URI is a kConfig error naming the URI part.
LinkResult<std::unique_ptr<GovernorLink>> open_link(const std::string& uri,
                                                    const LinkOptions& options = {});

}  // namespace drivers
