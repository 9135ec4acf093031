// A real MQTT broker and an independent subscriber for the fleet feed's tests: mosquitto on an
// ephemeral 127.0.0.1 port (its own config file in a temporary folder) and mosquitto_sub,
// both child processes killed when their objects go.
#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tests/integration/serve/child_process.hpp"

namespace rig::live::testing {

using plantsim::testing::ChildProcess;

// Absolute path of a program on PATH or in /usr/sbin (where Debian puts mosquitto); empty
// when absent.
std::string find_program(const std::string& name);
// A port nobody listens on right now (bound to 0 and released).
int free_port();

class Broker {
 public:
  explicit Broker(int port);  // starts it and waits until it accepts connections
  ~Broker();
  Broker(const Broker&) = delete;
  Broker& operator=(const Broker&) = delete;

  void kill();     // SIGKILL: connections drop without a word, retained messages are lost
  void restart();  // the same port again
  void signal(int sig) { process_->signal(sig); }  // SIGSTOP: a broker that hangs
  int port() const { return port_; }

 private:
  void start();

  int port_;
  std::filesystem::path dir_;
  std::unique_ptr<ChildProcess> process_;
};

// One message as mosquitto_sub prints it with -F '%r %q %t %p'.
struct MqttLine {
  bool retained = false;
  int qos = 0;
  std::string topic;
  std::string payload;
};

class Subscriber {
 public:
  // Subscribes to `filter` (QoS 1). count > 0: mosquitto_sub exits after that many messages.
  Subscriber(int port, const std::string& filter, int count = 0);
  // Returns once a probe published to `probe_topic` comes back, so that the subscription is
  // known to be in place; probes are not kept. False after `timeout`.
  bool wait_ready(const std::string& probe_topic, std::chrono::milliseconds timeout);
  // The next message (kept in lines()), nullopt on timeout.
  std::optional<MqttLine> next(std::chrono::milliseconds timeout);
  // Reads until a message on `topic` whose payload contains `needle`, looking first at the
  // messages read since the last wait_for() that matched.
  bool wait_for(const std::string& topic, const std::string& needle,
                std::chrono::milliseconds timeout);
  const std::vector<MqttLine>& lines() const { return lines_; }

 private:
  std::optional<MqttLine> read(std::chrono::milliseconds timeout);

  int port_;
  std::unique_ptr<ChildProcess> process_;
  std::string probe_topic_;
  std::vector<MqttLine> lines_;
  std::size_t scanned_ = 0;  // lines_ before this were looked at by wait_for()
};

// mosquitto_pub -t topic -m payload; true when it exited 0.
bool mqtt_pub(int port, const std::string& topic, const std::string& payload);

}  // namespace rig::live::testing
