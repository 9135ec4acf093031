#include "rig/live/mqtt_publisher.hpp"

#include <fmt/format.h>
#include <mosquitto.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace rig::live {
namespace {

using Clock = std::chrono::steady_clock;

// Keepalive: a rig that loses power or its network is declared dead (last will) by the broker
// after 1.5 keepalives without a packet; 10 s keeps "died" within 15 s at 1 ping per 10 s.
constexpr int kKeepaliveS = 10;
// Reconnection: 1 s after a loss (a restarted broker is back quickly), then 4, 9, 16, 25 s and
// at most every 30 s (squared backoff), so that a fleet does not hammer a broker that is down.
constexpr unsigned kReconnectDelayS = 1;
constexpr unsigned kReconnectDelayMaxS = 30;
// How long the reader sleeps at most between looks at the stop flag and new connections when
// the feed is quiet: the lag finish() and a reconnection's republishing may see.
constexpr std::chrono::milliseconds kReaderPoll{50};
// A clean disconnect gets this long even when finish()'s wait is spent: without it the broker
// would publish the last will ("died") for a run that ended normally.
constexpr std::chrono::milliseconds kDisconnectGrace{200};

constexpr std::string_view kRunning = R"({"status":"running"})";
constexpr std::string_view kEnded = R"({"status":"ended"})";
constexpr std::string_view kDied = R"({"status":"died"})";
constexpr const char* kStatusTopic = "status";
constexpr const char* kStateTopic = "state";

// Kinds published as they come (state is rate-limited apart); the topic is the kind's name.
// QoS 1 where a message matters on its own (an estimate, an alarm, how the run began and
// ended); QoS 0 where the next message supersedes it.
struct Route {
  const char* kind;
  int qos;
  bool retain;
};
constexpr Route kRoutes[] = {
    {kind::kStart, 1, true},  {kind::kOutcome, 1, true}, {kind::kEstimate, 1, false},
    {kind::kAlarm, 1, false}, {kind::kEvent, 0, false},  {kind::kTrend, 0, false},
};

void init_library_once() {
  static std::once_flag once;
  std::call_once(once, [] { mosquitto_lib_init(); });
}

[[noreturn]] void bad_uri(const std::string& uri, std::string_view why) {
  throw std::invalid_argument(
      fmt::format("--mqtt: expected mqtt://HOST[:PORT]/PREFIX, got '{}' ({})", uri, why));
}

int parse_port(const std::string& uri, std::string_view text) {
  constexpr int kMaxPort = 65535;
  if (text.empty() || text.size() > 5 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return std::isdigit(c) != 0; })) {
    bad_uri(uri, "the port must be a number 1-65535");
  }
  const int port = std::stoi(std::string(text));
  if (port < 1 || port > kMaxPort) bad_uri(uri, "the port must be a number 1-65535");
  return port;
}

// HOST, HOST:PORT, [IPv6] or [IPv6]:PORT.
void parse_authority(const std::string& uri, std::string_view authority, MqttTarget& target) {
  std::string_view host = authority;
  std::string_view after;  // what follows the host: empty or ":PORT"
  if (authority.starts_with('[')) {
    const auto close = authority.find(']');
    if (close == std::string_view::npos) bad_uri(uri, "no ']' after an IPv6 address");
    host = authority.substr(1, close - 1);
    after = authority.substr(close + 1);
    if (!after.empty() && !after.starts_with(':')) bad_uri(uri, "junk after ']'");
  } else if (const auto colon = authority.find(':'); colon != std::string_view::npos) {
    if (authority.find(':', colon + 1) != std::string_view::npos) {
      bad_uri(uri, "an IPv6 address needs brackets");
    }
    host = authority.substr(0, colon);
    after = authority.substr(colon);
  }
  if (host.empty()) bad_uri(uri, "no host");
  if (host.find('@') != std::string_view::npos) bad_uri(uri, "user names are not supported");
  target.host = std::string(host);
  if (!after.empty()) target.port = parse_port(uri, after.substr(1));
}

}  // namespace

MqttTarget parse_mqtt_uri(const std::string& uri) {
  constexpr std::string_view kScheme = "mqtt://";
  if (!uri.starts_with(kScheme)) bad_uri(uri, "the scheme must be mqtt://");
  const std::string_view rest = std::string_view(uri).substr(kScheme.size());
  const auto slash = rest.find('/');
  if (slash == std::string_view::npos) bad_uri(uri, "no topic prefix");
  MqttTarget target;
  parse_authority(uri, rest.substr(0, slash), target);

  std::string_view prefix = rest.substr(slash + 1);
  if (prefix.ends_with('/')) prefix.remove_suffix(1);
  if (prefix.empty()) bad_uri(uri, "the topic prefix is empty");
  if (prefix.find_first_of("+#") != std::string_view::npos) {
    bad_uri(uri, "the topic prefix may not contain '+' or '#'");
  }
  if (prefix.starts_with('/') || prefix.ends_with('/') ||
      prefix.find("//") != std::string_view::npos) {
    bad_uri(uri, "the topic prefix has an empty level");
  }
  target.prefix = std::string(prefix);
  return target;
}

struct MqttPublisher::Retained {
  MessagePtr start;
  MessagePtr outcome;
  MessagePtr state_pending;  // newer than the last state published, waiting for its turn
  MessagePtr state_sent;
  Clock::time_point state_due{};  // when the next state may go
};

MqttPublisher::MqttPublisher(const Feed& feed, MqttTarget target, std::string set_id)
    : feed_(feed), target_(std::move(target)), set_id_(std::move(set_id)) {
  if (set_id_.empty() || set_id_.find_first_of("/+#") != std::string::npos) {
    throw std::invalid_argument(fmt::format(
        "--set-id: '{}' must be one MQTT topic level (not empty, no '/', '+' or '#')", set_id_));
  }
  init_library_once();
  // No client id: the broker's random one, so that two rigs given the same set id do not
  // throw each other off. A clean session: the broker keeps nothing for a rig between runs.
  mosq_ = mosquitto_new(nullptr, true, this);
  if (mosq_ == nullptr) throw std::runtime_error("--mqtt: cannot create an MQTT client");
  try {
    start_network();
    reader_ = std::thread([this] { run_reader(); });
  } catch (...) {
    mosquitto_destroy(mosq_);  // cancels and joins libmosquitto's thread if it started
    throw;
  }
}

void MqttPublisher::start_network() {
  mosquitto_connect_callback_set(mosq_, &MqttPublisher::on_connect);
  mosquitto_disconnect_callback_set(mosq_, &MqttPublisher::on_disconnect);
  mosquitto_publish_callback_set(mosq_, &MqttPublisher::on_publish);
  const std::string will = topic(kStatusTopic);
  int rc = mosquitto_will_set(mosq_, will.c_str(), static_cast<int>(kDied.size()), kDied.data(), 1,
                              true);
  if (rc == MOSQ_ERR_SUCCESS) {
    rc = mosquitto_reconnect_delay_set(mosq_, kReconnectDelayS, kReconnectDelayMaxS, true);
  }
  // A refused or unreachable broker leaves the client connecting: its thread retries. Only a
  // request libmosquitto cannot even start is an error. The host name is resolved here, once.
  if (rc == MOSQ_ERR_SUCCESS) {
    rc = mosquitto_connect_async(mosq_, target_.host.c_str(), target_.port, kKeepaliveS);
    if (rc != MOSQ_ERR_INVAL && rc != MOSQ_ERR_NOMEM) rc = MOSQ_ERR_SUCCESS;
  }
  if (rc == MOSQ_ERR_SUCCESS) rc = mosquitto_loop_start(mosq_);
  if (rc != MOSQ_ERR_SUCCESS) {
    throw std::runtime_error(fmt::format("--mqtt: cannot start the MQTT client for {}:{}: {}",
                                         target_.host, target_.port, mosquitto_strerror(rc)));
  }
}

std::string MqttPublisher::topic(const char* name) const {
  return fmt::format("{}/{}/{}", target_.prefix, set_id_, name);
}

// The reader: follows the feed in batches (since() copies pointers under the feed's lock and
// releases it), hands each message to libmosquitto (which only queues it), and sleeps on the
// feed until there is more, a state is due, or finish() asks it to stop.
void MqttPublisher::run_reader() {
  Retained retained;
  std::uint64_t cursor = 0;
  int resynced = 0;  // connections the retained topics were published again for
  for (;;) {
    bool stop = false;
    int connections = 0;
    {
      const std::lock_guard lock(mutex_);
      stop = stop_;
      connections = connections_;
    }
    if (connections > resynced) {
      republish(retained, connections > 1);
      resynced = connections;
    }
    const std::vector<MessagePtr> batch = feed_.since(cursor);
    for (const MessagePtr& m : batch) {
      cursor = m->seq;
      route(m, retained);
    }
    const auto now = Clock::now();
    const bool drained = batch.empty();
    if (retained.state_pending && ((drained && stop) || now >= retained.state_due)) {
      publish(topic(kStateTopic), retained.state_pending->json, 0, true);
      retained.state_sent = std::move(retained.state_pending);
      retained.state_pending = nullptr;
      retained.state_due = now + kStateInterval;
    }
    if (!drained) continue;  // a full batch: there may be more at once
    if (stop) return;
    auto nap = kReaderPoll;
    if (retained.state_pending) {
      nap = std::clamp(std::chrono::ceil<std::chrono::milliseconds>(retained.state_due - now),
                       std::chrono::milliseconds(1), kReaderPoll);
    }
    if (!feed_.closed()) {
      feed_.wait(cursor, nap);
    } else {  // a closed feed's wait() returns at once: wait for finish() instead
      std::unique_lock lock(mutex_);
      cv_.wait_for(lock, nap, [&] { return stop_ || connections_ > resynced; });
    }
  }
}

void MqttPublisher::route(const MessagePtr& m, Retained& retained) {
  if (m->kind == kind::kState) {
    retained.state_pending = m;
    return;
  }
  for (const Route& r : kRoutes) {
    if (m->kind != r.kind) continue;
    if (m->kind == kind::kStart) retained.start = m;
    if (m->kind == kind::kOutcome) retained.outcome = m;
    publish(topic(r.kind), m->json, r.qos, r.retain);
    return;
  }
  // sample, bode, sweep_point, timing: the live page's, not the fleet's
}

// After a connection: the latest state again (a state published while the first connection
// was still being made found no connection), and after a reconnection also start and
// outcome, which a broker restarted without persistence has forgotten. Retained topics take
// a repeat as the same value.
void MqttPublisher::republish(Retained& retained, bool reconnected) {
  if (retained.state_sent && !retained.state_pending) {
    publish(topic(kStateTopic), retained.state_sent->json, 0, true);
  }
  if (!reconnected) return;
  if (retained.start) publish(topic(kind::kStart), retained.start->json, 1, true);
  if (retained.outcome) publish(topic(kind::kOutcome), retained.outcome->json, 1, true);
}

// Hands one message to libmosquitto, which queues it for its network thread and returns at
// once. A QoS 1 message finding no connection stays queued (sent on reconnection); QoS 0 is
// refused. The outstanding count is the bound: on_publish takes a message off it.
bool MqttPublisher::publish(const std::string& topic, const std::string& payload, int qos,
                            bool retain) {
  {
    const std::lock_guard lock(mutex_);
    if (outstanding_.size() >= kMaxOutstanding) {
      ++dropped_;
      return false;
    }
  }
  int mid = 0;
  const int rc = mosquitto_publish(mosq_, &mid, topic.c_str(), static_cast<int>(payload.size()),
                                   payload.data(), qos, retain);
  const bool queued = rc == MOSQ_ERR_SUCCESS || (qos > 0 && rc == MOSQ_ERR_NO_CONN);
  const std::lock_guard lock(mutex_);
  if (!queued) {
    ++dropped_;
    return false;
  }
  if (early_acks_.erase(mid) > 0) {
    ++published_;
  } else {
    outstanding_.emplace(mid, qos);
  }
  return true;
}

void MqttPublisher::on_connect(mosquitto* /*mosq*/, void* self, int rc) {
  if (rc != 0) return;  // refused (CONNACK code): libmosquitto retries
  auto* p = static_cast<MqttPublisher*>(self);
  bool ending = false;
  {
    const std::lock_guard lock(p->mutex_);
    p->connected_ = true;
    ++p->connections_;
    ending = p->stop_;
  }
  p->cv_.notify_all();
  // Not once finish() has begun: "running" queued after "ended" would be the status kept.
  if (!ending) p->publish(p->topic(kStatusTopic), std::string(kRunning), 1, true);
}

// QoS 0 messages not yet written when a connection goes are lost with it (libmosquitto
// clears its packet queue on reconnection); QoS 1 ones stay queued and are sent again.
void MqttPublisher::on_disconnect(mosquitto* /*mosq*/, void* self, int /*rc*/) {
  auto* p = static_cast<MqttPublisher*>(self);
  {
    const std::lock_guard lock(p->mutex_);
    p->connected_ = false;
    std::erase_if(p->outstanding_, [&](const auto& entry) {
      if (entry.second != 0) return false;
      ++p->dropped_;
      return true;
    });
  }
  p->cv_.notify_all();
}

// Runs on libmosquitto's thread, possibly before the mosquitto_publish() call that sent the
// message has returned: then the id waits in early_acks_ for publish() to find it.
void MqttPublisher::on_publish(mosquitto* /*mosq*/, void* self, int mid) {
  auto* p = static_cast<MqttPublisher*>(self);
  {
    const std::lock_guard lock(p->mutex_);
    if (p->outstanding_.erase(mid) > 0) {
      ++p->published_;
    } else {
      // Bounded in case an id never comes back from publish() (no such path is known).
      if (p->early_acks_.size() >= kMaxOutstanding) p->early_acks_.clear();
      p->early_acks_.insert(mid);
    }
  }
  p->cv_.notify_all();
}

void MqttPublisher::finish(std::chrono::milliseconds max_wait) {
  if (finished_) return;
  finished_ = true;
  const auto deadline = Clock::now() + max_wait;
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (reader_.joinable()) reader_.join();
  publish(topic(kStatusTopic), std::string(kEnded), 1, true);
  wait_for_outstanding(deadline);
  disconnect(deadline);
}

void MqttPublisher::wait_for_outstanding(Clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  cv_.wait_until(lock, deadline, [&] { return outstanding_.empty(); });
}

// A clean disconnect when connected: the broker drops the last will. Then libmosquitto's
// thread is cancelled rather than joined politely: after a clean disconnect it has nothing
// left to do, and otherwise it may be sleeping before a reconnection or in a connect() to an
// unreachable host, which mosquitto_disconnect() does not interrupt (a reconnection under way
// even undoes it). mosquitto_destroy() takes no lock the cancelled thread could have held.
void MqttPublisher::disconnect(Clock::time_point deadline) {
  bool was_connected = false;
  {
    const std::lock_guard lock(mutex_);
    was_connected = connected_;
  }
  mosquitto_disconnect(mosq_);
  if (was_connected) {
    std::unique_lock lock(mutex_);
    cv_.wait_until(lock, std::max(deadline, Clock::now() + kDisconnectGrace),
                   [&] { return !connected_; });
  }
  mosquitto_loop_stop(mosq_, true);
  mosquitto_destroy(mosq_);
  mosq_ = nullptr;
  const std::lock_guard lock(mutex_);
  dropped_ += outstanding_.size();  // never to be acknowledged now
  outstanding_.clear();
}

MqttPublisher::~MqttPublisher() {
  try {
    finish();
  } catch (...) {  // a destructor must not throw; the publisher is best effort anyway
  }
}

std::size_t MqttPublisher::published() const {
  const std::lock_guard lock(mutex_);
  return published_;
}

std::size_t MqttPublisher::dropped() const {
  const std::lock_guard lock(mutex_);
  return dropped_;
}

}  // namespace rig::live
