// The live outputs of a session command (--http, --mqtt, --set-id; docs/live.md): the feed
// the tick loop publishes, the live page serving it and the fleet feed following it. Built
// before the session, closed after it; a command without either option has none.
#pragma once

#include <atomic>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "rig/live/feed.hpp"

namespace rig::live {
class LiveServer;
class MqttPublisher;
}  // namespace rig::live

namespace rig::cli {

struct LiveArgs {
  std::string http;    // HOST:PORT or PORT ("" off)
  std::string mqtt;    // mqtt://HOST[:PORT]/PREFIX ("" off)
  std::string set_id;  // the set's id in topics and titles ("" the host name)
};

class LiveOutputs {
 public:
  // Throws session::ConfigError (exit 2) for a malformed option or an address it cannot bind.
  // stop is what the page's Stop button sets (the command's SIGINT flag).
  LiveOutputs(const LiveArgs& args, const std::string& command, std::atomic<bool>& stop);
  ~LiveOutputs();
  LiveOutputs(const LiveOutputs&) = delete;
  LiveOutputs& operator=(const LiveOutputs&) = delete;

  // The feed, or nullptr when neither --http nor --mqtt was given.
  live::Feed* feed() { return on_ ? &feed_ : nullptr; }
  // The command's end: publishes the outcome (unless the command did), closes the feed, lets
  // the page and the broker take the last messages, stops serving.
  void finish(int exit_code);

 private:
  bool on_ = false;
  live::Feed feed_;
  std::unique_ptr<live::LiveServer> server_;
  std::unique_ptr<live::MqttPublisher> mqtt_;
  bool finished_ = false;
};

// The set id when none is given: the host name ("rig" when it has none).
std::string default_set_id();

}  // namespace rig::cli
