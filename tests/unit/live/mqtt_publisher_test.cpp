// The fleet feed against a real mosquitto broker, seen by mosquitto_sub: what arrives on which
// topic with which flags, the state's rate limit, the retained topics a late dashboard sees,
// the last will after SIGKILL, no blocking without a broker, and a broker restarted mid-run.
#include "rig/live/mqtt_publisher.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "rig/live/feed.hpp"
#include "tests/unit/live/mqtt_broker.hpp"

namespace rig::live {
namespace {

using namespace std::chrono_literals;
using testing::Broker;
using testing::MqttLine;
using testing::Subscriber;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

// Generous for a loaded 2-core machine; a passing run waits far less.
constexpr auto kArrival = 10s;

class MqttPublisherTest : public ::testing::Test {
 protected:
  void SetUp() override { broker_ = std::make_unique<Broker>(testing::free_port()); }

  MqttTarget target(const std::string& prefix) const {
    return {"127.0.0.1", broker_->port(), prefix};
  }
  // A subscriber to PREFIX/# known to be subscribed.
  std::unique_ptr<Subscriber> subscribe(const std::string& prefix) const {
    auto sub = std::make_unique<Subscriber>(broker_->port(), prefix + "/#");
    EXPECT_TRUE(sub->wait_ready(prefix + "/probe", kArrival));
    return sub;
  }
  // Reads `count` messages on `filter`: what a dashboard connecting now is given (the
  // retained ones).
  std::map<std::string, MqttLine> retained(const std::string& filter, int count) const {
    Subscriber late(broker_->port(), filter, count);
    std::map<std::string, MqttLine> by_topic;
    for (int i = 0; i < count; ++i) {
      const auto line = late.next(kArrival);
      if (!line) break;
      by_topic[line->topic] = *line;
    }
    return by_topic;
  }

  std::unique_ptr<Broker> broker_;
};

std::map<std::string, int> count_topics(const std::vector<MqttLine>& lines) {
  std::map<std::string, int> n;
  for (const MqttLine& l : lines) ++n[l.topic];
  return n;
}

// A commissioning-like feed for ~1.5 s of wall time: a state and a sample every 10 ms, two
// estimates per tick for the first 100 ticks, one of each other kind in the middle.
TEST_F(MqttPublisherTest, FeedArrivesOnItsTopicsWithStateRateLimitedAndRetainedEnd) {
  const std::string prefix = "fleet/north";
  const std::string base = prefix + "/set-07/";
  auto sub = subscribe(prefix);
  Feed feed;
  MqttPublisher pub(feed, target(prefix), "set-07");
  ASSERT_TRUE(sub->wait_for(base + "status", R"({"status":"running"})", kArrival));

  constexpr int kTicks = 150;
  constexpr int kEstimates = 200;
  const auto t0 = Clock::now();
  feed.publish(kind::kStart, {{"command", "commission"}});
  int estimates = 0;
  for (int i = 0; i < kTicks; ++i) {
    feed.publish(kind::kState, {{"i", i}});
    feed.publish(kind::kSample, {{"i", i}});
    for (int k = 0; k < 2 && estimates < kEstimates; ++k) {
      feed.publish(kind::kEstimate, {{"n", estimates++}});
    }
    if (i == kTicks / 2) {
      for (const char* k : {kind::kEvent, kind::kAlarm, kind::kTrend, kind::kBode,
                            kind::kSweepPoint, kind::kTiming}) {
        feed.publish(k, {{"kind", k}});
      }
    }
    std::this_thread::sleep_for(10ms);
  }
  feed.publish(kind::kOutcome, {{"exit_code", 0}});
  feed.close();
  pub.finish();
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();

  ASSERT_TRUE(sub->wait_for(base + "status", R"({"status":"ended"})", kArrival));
  while (sub->next(200ms)) {
  }
  const auto n = count_topics(sub->lines());
  EXPECT_EQ(n.at(base + "estimate"), kEstimates);
  int next_estimate = 0;
  std::string last_state;
  for (const MqttLine& l : sub->lines()) {
    if (l.topic == base + "estimate") {
      EXPECT_EQ(json::parse(l.payload)["n"], next_estimate++);
    }
    if (l.topic == base + "state") last_state = l.payload;
  }
  for (const char* once : {"start", "event", "alarm", "trend", "outcome"}) {
    EXPECT_EQ(n.count(base + once) ? n.at(base + once) : 0, 1) << once;
  }
  for (const char* never : {"sample", "bode", "sweep_point", "timing"}) {
    EXPECT_EQ(n.count(base + never), 0u) << never;
  }
  // One state at once, one per second after, and the latest at the end.
  EXPECT_GE(n.at(base + "state"), 2);
  EXPECT_LE(n.at(base + "state"), static_cast<int>(std::floor(elapsed_s)) + 2);
  EXPECT_EQ(last_state, R"({"i":149})");
  EXPECT_EQ(n.at(base + "status"), 2);  // running, ended
  EXPECT_EQ(pub.dropped(), 0u);
  EXPECT_EQ(pub.published(), sub->lines().size());

  const auto kept = retained(prefix + "/#", 4);
  ASSERT_EQ(kept.size(), 4u);
  for (const auto& [topic, line] : kept) EXPECT_TRUE(line.retained) << topic;
  EXPECT_EQ(kept.at(base + "start").payload, R"({"command":"commission"})");
  EXPECT_EQ(kept.at(base + "state").payload, R"({"i":149})");
  EXPECT_EQ(kept.at(base + "outcome").payload, R"({"exit_code":0})");
  EXPECT_EQ(kept.at(base + "status").payload, R"({"status":"ended"})");
  EXPECT_EQ(kept.at(base + "start").qos, 1);
}

// The publisher runs in a forked child that is SIGKILLed: no DISCONNECT reaches the broker,
// which publishes the last will.
TEST_F(MqttPublisherTest, SigkillLeavesDiedRetained) {
  const std::string prefix = "fleet/south";
  const std::string status = prefix + "/victim/status";
  auto sub = subscribe(prefix);
  const MqttTarget where = target(prefix);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      Feed feed;
      MqttPublisher pub(feed, where, "victim");
      feed.publish(kind::kStart, {{"command", "monitor"}});
      for (;;) pause();
    } catch (...) {
    }
    _exit(1);
  }
  const bool running = sub->wait_for(status, R"({"status":"running"})", kArrival);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  ASSERT_TRUE(running);
  ASSERT_TRUE(sub->wait_for(status, R"({"status":"died"})", kArrival));

  const auto kept = retained(status, 1);
  ASSERT_EQ(kept.count(status), 1u);
  EXPECT_TRUE(kept.at(status).retained);
  EXPECT_EQ(kept.at(status).payload, R"({"status":"died"})");
}

// Publishes a mix of estimates (QoS 1), events (QoS 0) and states; returns how many of the
// first two kinds.
int publish_mix(Feed& feed, int messages) {
  int counted = 0;
  for (int i = 0; i < messages; ++i) {
    switch (i % 3) {
      case 0:
        feed.publish(kind::kEstimate, {{"n", i}});
        ++counted;
        break;
      case 1:
        feed.publish(kind::kEvent, {{"n", i}});
        ++counted;
        break;
      default:
        feed.publish(kind::kState, {{"n", i}});
    }
  }
  return counted;
}

// Nothing listens: QoS 0 finds no connection, QoS 1 fills libmosquitto's queue up to the bound
// and the rest is dropped; neither publishing nor finish() waits for a broker.
TEST(MqttPublisherNoBroker, NeverBlocks) {
  constexpr int kMessages = 10000;
  Feed feed;
  const auto t0 = Clock::now();
  MqttPublisher pub(feed, {"127.0.0.1", testing::free_port(), "fleet"}, "set-01");
  const int counted = publish_mix(feed, kMessages);
  feed.close();
  pub.finish(200ms);
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_LT(elapsed_s, 1.0);
  EXPECT_EQ(pub.published(), 0u);
  EXPECT_GE(pub.dropped(), static_cast<std::size_t>(counted));
}

// The broker hangs (SIGSTOP) with the connection open: nothing is acknowledged, QoS 1 fills
// the bound and the rest is dropped; finish() gives up after its wait.
TEST_F(MqttPublisherTest, HungBrokerNeverBlocks) {
  constexpr int kMessages = 10000;
  const std::string prefix = "fleet/west";
  auto sub = subscribe(prefix);
  Feed feed;
  MqttPublisher pub(feed, target(prefix), "set-05");
  ASSERT_TRUE(sub->wait_for(prefix + "/set-05/status", "running", kArrival));
  broker_->signal(SIGSTOP);
  const auto t0 = Clock::now();
  publish_mix(feed, kMessages);
  feed.close();
  pub.finish(200ms);
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
  broker_->signal(SIGCONT);
  EXPECT_LT(elapsed_s, 1.0);
  // At least every estimate past the bound.
  EXPECT_GE(pub.dropped(),
            static_cast<std::size_t>(kMessages / 3 - MqttPublisher::kMaxOutstanding));
}

// The broker dies mid-run and comes back on the same port: the publisher reconnects by itself,
// what it queued (QoS 1) during the outage and what comes after reach the new broker, and the
// retained start, which the killed broker lost, is published again.
TEST_F(MqttPublisherTest, BrokerRestartedMidRun) {
  const std::string prefix = "fleet/east";
  const std::string base = prefix + "/set-03/";
  auto sub = subscribe(prefix);
  Feed feed;
  MqttPublisher pub(feed, target(prefix), "set-03");
  ASSERT_TRUE(sub->wait_for(base + "status", "running", kArrival));
  feed.publish(kind::kStart, {{"command", "monitor"}});
  int n = 0;
  auto estimates = [&](int count) {
    for (int i = 0; i < count; ++i) feed.publish(kind::kEstimate, {{"n", n++}});
  };
  estimates(50);
  ASSERT_TRUE(sub->wait_for(base + "estimate", R"({"n":49})", kArrival));

  broker_->kill();
  sub.reset();
  estimates(50);  // during the outage
  std::this_thread::sleep_for(300ms);
  broker_->restart();
  sub = subscribe(prefix);
  ASSERT_TRUE(sub->wait_for(base + "status", "running", kArrival));
  estimates(50);
  ASSERT_TRUE(sub->wait_for(base + "estimate", R"({"n":149})", kArrival));
  feed.close();
  pub.finish();

  std::map<int, int> seen;
  for (const MqttLine& l : sub->lines()) {
    if (l.topic == base + "estimate") ++seen[json::parse(l.payload)["n"].get<int>()];
  }
  for (int i = 100; i < 150; ++i) EXPECT_EQ(seen[i], 1) << "estimate " << i;
  // Every message was taken by a broker (the outage's from the queue, after reconnection).
  EXPECT_EQ(pub.dropped(), 0u);
  const auto kept = retained(prefix + "/#", 2);  // start and status
  ASSERT_EQ(kept.count(base + "start"), 1u);
  EXPECT_EQ(kept.at(base + "start").payload, R"({"command":"monitor"})");
  EXPECT_EQ(kept.at(base + "status").payload, R"({"status":"ended"})");
}

}  // namespace
}  // namespace rig::live
