// --mqtt's URI and --set-id: what is accepted, and that every refusal is one line naming the
// option and what was expected.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "rig/live/mqtt_publisher.hpp"

namespace rig::live {
namespace {

TEST(MqttUri, HostPortAndPrefix) {
  const MqttTarget t = parse_mqtt_uri("mqtt://10.0.0.2:1884/fleet");
  EXPECT_EQ(t.host, "10.0.0.2");
  EXPECT_EQ(t.port, 1884);
  EXPECT_EQ(t.prefix, "fleet");
}

TEST(MqttUri, DefaultPortAndPrefixWithLevels) {
  const MqttTarget t = parse_mqtt_uri("mqtt://broker.example.org/site/north/gensets");
  EXPECT_EQ(t.host, "broker.example.org");
  EXPECT_EQ(t.port, 1883);
  EXPECT_EQ(t.prefix, "site/north/gensets");
}

TEST(MqttUri, BracketedIpv6AndTrailingSlash) {
  const MqttTarget t = parse_mqtt_uri("mqtt://[::1]:8883/fleet/");
  EXPECT_EQ(t.host, "::1");
  EXPECT_EQ(t.port, 8883);
  EXPECT_EQ(t.prefix, "fleet");
  EXPECT_EQ(parse_mqtt_uri("mqtt://[fe80::2]/p").port, 1883);
}

TEST(MqttUri, RefusalsNameTheOptionOnOneLine) {
  const char* bad[] = {
      "",
      "broker:1883/fleet",
      "http://broker/fleet",
      "mqtts://broker/fleet",
      "mqtt://broker",
      "mqtt://broker/",
      "mqtt:///fleet",
      "mqtt://:1883/fleet",
      "mqtt://broker:/fleet",
      "mqtt://broker:0/fleet",
      "mqtt://broker:65536/fleet",
      "mqtt://broker:18a3/fleet",
      "mqtt://broker:-1/fleet",
      "mqtt://::1:1883/fleet",
      "mqtt://[::1/fleet",
      "mqtt://[::1]x/fleet",
      "mqtt://user:pw@broker/fleet",
      "mqtt://broker/fleet/#",
      "mqtt://broker/fleet/+/x",
      "mqtt://broker//fleet",
      "mqtt://broker/a//b",
  };
  for (const char* uri : bad) {
    try {
      parse_mqtt_uri(uri);
      ADD_FAILURE() << "accepted " << uri;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("--mqtt: expected mqtt://HOST[:PORT]/PREFIX", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

TEST(MqttSetId, IsOneTopicLevel) {
  Feed feed;
  const MqttTarget target{"127.0.0.1", 1, "fleet"};
  for (const char* id : {"", "a/b", "a+", "#"}) {
    try {
      MqttPublisher pub(feed, target, id);
      ADD_FAILURE() << "accepted set id '" << id << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--set-id: ", 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace rig::live
