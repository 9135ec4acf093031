// The live page's server against cpp-httplib's own client (a second implementation of the
// protocol side): routes, the event stream with resume, the stop token.
#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <cstring>
#include <regex>

#include "rig/live/http_server.hpp"

namespace rig::live {
namespace {

TEST(LiveServer, AddressIsHostPortOrPortOnLoopback) {
  EXPECT_EQ(parse_http_address("8080").host, "127.0.0.1");
  EXPECT_EQ(parse_http_address("8080").port, 8080);
  EXPECT_EQ(parse_http_address("0.0.0.0:9000").host, "0.0.0.0");
  EXPECT_EQ(parse_http_address("0.0.0.0:9000").port, 9000);
  EXPECT_EQ(parse_http_address("0").port, 0);
  for (const char* bad : {"", "x", "host:", ":80", "127.0.0.1:70000", "127.0.0.1:-1", "80x"}) {
    try {
      parse_http_address(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("--http"), std::string::npos) << e.what();
    }
  }
}

TEST(LiveServer, TokensAreLongAndDiffer) {
  const std::string a = new_stop_token(), b = new_stop_token();
  EXPECT_TRUE(std::regex_match(a, std::regex("[0-9a-f]{32}")));
  EXPECT_NE(a, b);
}

struct Served {
  Feed feed;
  std::atomic<int> stops{0};
  LiveServer server{feed, HttpAddress{"127.0.0.1", 0}, "secret-token-0123456789abcdef0123", "test",
                    [this] { ++stops; }};
  int port() const { return std::stoi(server.url().substr(std::strlen("http://127.0.0.1:"))); }
  httplib::Client client() const { return httplib::Client("127.0.0.1", port()); }
};

TEST(LiveServer, ServesThePageAndTheLatestState) {
  Served s;
  s.feed.publish(kind::kStart, {{"command", "commission"}});
  s.feed.publish(kind::kState, {{"phase", "pilot"}});
  auto c = s.client();
  const auto page = c.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("uPlot"), std::string::npos);
  EXPECT_NE(page->body.find("EventSource('events')"), std::string::npos);
  const auto state = c.Get("/state");
  ASSERT_TRUE(state);
  const auto j = nlohmann::json::parse(state->body);
  EXPECT_EQ(j["state"]["phase"], "pilot");
  EXPECT_EQ(j["start"]["command"], "commission");
  EXPECT_TRUE(j["outcome"].is_null());
  EXPECT_EQ(c.Get("/nothing")->status, 404);
}

TEST(LiveServer, EventStreamSendsHistoryThenEndsWhenTheFeedCloses) {
  Served s;
  for (int i = 0; i < 3; ++i) s.feed.publish(kind::kSample, {{"i", i}});
  s.feed.publish(kind::kOutcome, {{"exit_code", 0}});
  s.feed.close();
  auto c = s.client();
  const auto all = c.Get("/events");
  ASSERT_TRUE(all);
  EXPECT_EQ(all->get_header_value("Content-Type"), "text/event-stream");
  // Consecutive samples go as one event with their array, its id the last one's.
  EXPECT_EQ(all->body,
            "id: 3\nevent: samples\ndata: [{\"i\":0},{\"i\":1},{\"i\":2}]\n\n"
            "id: 4\nevent: outcome\ndata: {\"exit_code\":0}\n\n");
  // A browser reconnecting after id 2 gets 3 and 4 only.
  const auto rest = c.Get("/events", {{"Last-Event-ID", "2"}});
  ASSERT_TRUE(rest);
  EXPECT_EQ(rest->body,
            "id: 3\nevent: samples\ndata: [{\"i\":2}]\n\n"
            "id: 4\nevent: outcome\ndata: {\"exit_code\":0}\n\n");
}

TEST(LiveServer, StopNeedsTheRunsToken) {
  Served s;
  auto c = s.client();
  EXPECT_EQ(c.Post("/stop", "", "text/plain")->status, 403);
  EXPECT_EQ(c.Post("/stop", {{"X-Rig-Token", "wrong"}}, "", "text/plain")->status, 403);
  EXPECT_EQ(c.Post("/stop", {{"X-Rig-Token", "secret-token-0123456789abcdef012"}}, "", "text/plain")
                ->status,
            403);  // one character short
  EXPECT_EQ(s.stops.load(), 0);
  EXPECT_EQ(
      c.Post("/stop", {{"X-Rig-Token", "secret-token-0123456789abcdef0123"}}, "", "text/plain")
          ->status,
      202);
  EXPECT_EQ(c.Post("/stop", "token=secret-token-0123456789abcdef0123",
                   "application/x-www-form-urlencoded")
                ->status,
            202);
  EXPECT_EQ(s.stops.load(), 2);
  // Read-only otherwise: no other method or path changes anything.
  EXPECT_NE(c.Put("/stop", "", "text/plain")->status, 202);
  EXPECT_EQ(c.Post("/state", "", "text/plain")->status, 404);
}

TEST(LiveServer, APortInUseIsRefusedWithTheAddress) {
  Served s;
  const int port = s.port();
  try {
    LiveServer second(s.feed, HttpAddress{"127.0.0.1", port}, "t", "test", [] {});
    ADD_FAILURE() << "bound twice";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(port)), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rig::live
