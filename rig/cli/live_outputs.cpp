#include "rig/cli/live_outputs.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <stdexcept>

#include "rig/live/http_server.hpp"
#include "rig/live/mqtt_publisher.hpp"
#include "rig/session/test_config.hpp"

namespace rig::cli {

std::string default_set_id() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "rig";
  return name;
}

LiveOutputs::LiveOutputs(const LiveArgs& args, const std::string& command,
                         std::atomic<bool>& stop) {
  on_ = !args.http.empty() || !args.mqtt.empty();
  if (!on_) return;
  const std::string set_id = args.set_id.empty() ? default_set_id() : args.set_id;
  feed_.publish(live::kind::kStart, {{"command", command}, {"set_id", set_id}});
  try {
    if (!args.mqtt.empty()) {
      // A broker that is down is no error (it retries); a malformed --mqtt or --set-id is.
      mqtt_ = std::make_unique<live::MqttPublisher>(feed_, live::parse_mqtt_uri(args.mqtt), set_id);
      fmt::print(stderr, "rig {}: fleet feed {} as set {}\n", command, args.mqtt, set_id);
    }
    if (!args.http.empty()) {
      const live::HttpAddress address = live::parse_http_address(args.http);
      const std::string token = live::new_stop_token();
      server_ = std::make_unique<live::LiveServer>(
          feed_, address, token, fmt::format("rig {} on {}: live", command, set_id),
          [&stop] { stop.store(true); });
      // The token goes to the console only: whoever can reach the port cannot stop the test.
      fmt::print(stderr, "rig {}: live page {} (stop token {})\n", command, server_->url(), token);
    }
  } catch (const std::exception& e) {
    throw session::ConfigError(e.what());
  }
}

void LiveOutputs::finish(int exit_code) {
  if (!on_ || finished_) return;
  finished_ = true;
  if (!feed_.latest(live::kind::kOutcome)) {
    feed_.publish(live::kind::kOutcome, {{"exit_code", exit_code}, {"outcome", ""}});
  }
  feed_.close();
  if (mqtt_) mqtt_->finish();
  if (server_) server_->stop();
}

LiveOutputs::~LiveOutputs() { finish(-1); }

}  // namespace rig::cli
