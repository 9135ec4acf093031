// The fleet feed (DESIGN.md section 10, docs/live-mqtt.md): a set under test or under watch
// publishes its state, estimates, alarms and outcome to an MQTT broker (--mqtt), so that a
// fleet's dashboard sees every set without talking to the rigs.
//
//   MqttPublisher pub(feed, parse_mqtt_uri("mqtt://10.0.0.2:1883/site/north"), "set-07");
//   ... the tick loop publishes to `feed` ...
//   feed.close();
//   pub.finish();   // what is left, status "ended", clean disconnect
//
// A broker that is down, slow or restarting never affects the test: libmosquitto's own thread
// does the network, a reader thread follows the feed (whose loop side never waits for a reader)
// and hands messages to libmosquitto without waiting for the broker. What libmosquitto holds
// unacknowledged is bounded (kMaxOutstanding); beyond that, and whatever QoS 0 finds no
// connection, is dropped and counted. The connection retries in the background.
//
// Topics PREFIX/SET_ID/<topic>:
//   start    retained, QoS 1    state  retained, QoS 0, at most one per second (the latest)
//   estimate QoS 1              event  QoS 0
//   alarm    QoS 1              trend  QoS 0
//   outcome  retained, QoS 1    status retained, QoS 1: {"status":"running"} on every
//            connection, {"status":"ended"} from finish(), {"status":"died"} as the last will
// sample, bode, sweep_point and timing stay on the live page: too frequent or too large.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include "rig/live/feed.hpp"

struct mosquitto;

namespace rig::live {

struct MqttTarget {
  std::string host;
  int port = 1883;
  std::string prefix;  // topic levels before the set id, e.g. "site/north"
};

// "mqtt://HOST[:PORT]/PREFIX" (HOST may be a bracketed IPv6 address; PREFIX may contain '/',
// is non-empty and has no '+', '#' or empty level; one trailing '/' is ignored).
// Throws std::invalid_argument with a one-line message naming --mqtt and what was expected.
MqttTarget parse_mqtt_uri(const std::string& uri);

class MqttPublisher {
 public:
  // Messages libmosquitto may hold that the broker has not taken yet (QoS 0 not yet written,
  // QoS 1 not yet acknowledged). At a few estimates a second this is minutes of outage kept
  // for the broker's return, and at most a few MB of memory.
  static constexpr std::size_t kMaxOutstanding = 1000;
  // At most one state per this wall time: a dashboard refreshes no faster, and a fleet of
  // sets at the loop's rate would load the broker for nothing.
  static constexpr std::chrono::milliseconds kStateInterval{1000};

  // Starts libmosquitto's network thread and an asynchronous connection (a broker that is
  // down is not an error: it retries in the background), with the last will
  // PREFIX/SET_ID/status = {"status":"died"} retained, and a reader thread that follows the
  // feed. Throws std::invalid_argument when set_id is empty or has '/', '+' or '#' (naming
  // --set-id), std::runtime_error when libmosquitto cannot start.
  MqttPublisher(const Feed& feed, MqttTarget target, std::string set_id);
  // Publishes what is left of the feed and the latest state, publishes status
  // {"status":"ended"} retained, waits at most max_wait for the broker to take what is
  // outstanding, and disconnects cleanly (the broker drops the last will), allowing the
  // disconnect itself 200 ms more. Called once the feed is closed; later calls do nothing.
  void finish(std::chrono::milliseconds max_wait = std::chrono::seconds(2));
  ~MqttPublisher();  // finish() if not done; never throws

  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  // Messages the broker took (QoS 0 written to its socket, QoS 1 acknowledged).
  std::size_t published() const;
  // Messages given up: kMaxOutstanding reached, QoS 0 without a connection, lost with a
  // connection, or still unacknowledged when finish() gave up waiting.
  std::size_t dropped() const;

 private:
  struct Retained;  // the latest start, state and outcome the reader has seen

  void start_network();
  void run_reader();
  void route(const MessagePtr& m, Retained& retained);
  void republish(Retained& retained, bool reconnected);
  bool publish(const std::string& topic, const std::string& payload, int qos, bool retain);
  void wait_for_outstanding(std::chrono::steady_clock::time_point deadline);
  void disconnect(std::chrono::steady_clock::time_point deadline);
  std::string topic(const char* name) const;

  static void on_connect(mosquitto* mosq, void* self, int rc);
  static void on_disconnect(mosquitto* mosq, void* self, int rc);
  static void on_publish(mosquitto* mosq, void* self, int mid);

  const Feed& feed_;
  const MqttTarget target_;
  const std::string set_id_;
  mosquitto* mosq_ = nullptr;
  std::thread reader_;
  bool finished_ = false;

  mutable std::mutex mutex_;  // everything below; never held while calling libmosquitto
  std::condition_variable cv_;
  bool stop_ = false;
  bool connected_ = false;
  int connections_ = 0;                       // successful connections so far
  std::unordered_map<int, int> outstanding_;  // message id -> QoS, handed to libmosquitto
  std::unordered_set<int> early_acks_;        // on_publish ran before mosquitto_publish returned
  std::size_t published_ = 0;
  std::size_t dropped_ = 0;
};

}  // namespace rig::live
