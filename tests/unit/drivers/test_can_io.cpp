#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>

#include "drivers/can/frame_io.hpp"
#include "drivers/can/j1939.hpp"
#include "drivers/can/transport.hpp"

namespace j = drivers::j1939;
using drivers::LinkErrorKind;
using drivers::can::CanRole;
using namespace std::chrono_literals;

namespace {

struct SocketPair {
  int fd[2] = {-1, -1};
  SocketPair() { EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fd), 0); }
  ~SocketPair() {
    for (int f : fd)
      if (f >= 0) ::close(f);
  }
  void close_end(int i) {
    ::close(fd[i]);
    fd[i] = -1;
  }
};

drivers::LinkUri udp_uri(int port) {
  auto u = drivers::parse_link_uri("can+udp://127.0.0.1:" + std::to_string(port));
  EXPECT_TRUE(u);
  return u.value();
}

}  // namespace

TEST(CanFrameIo, RoundTripOverSocketpair) {
  SocketPair sp;
  const can_frame sent = j::encode_plant_sample({3.5e6, 42, 0x07});
  ASSERT_TRUE(drivers::can::write_frame(sp.fd[0], sent, "pair"));
  auto got = drivers::can::read_frame(sp.fd[1], 100ms, "pair");
  ASSERT_TRUE(got) << got.error().message();
  EXPECT_EQ(got->can_id, sent.can_id);
  EXPECT_EQ(got->can_dlc, 8);
  auto d = j::decode_plant_sample(*got);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->counter, 42);
  EXPECT_DOUBLE_EQ(d->power_w, 3.5e6);
}

TEST(CanFrameIo, TimeoutWhenNothingArrives) {
  SocketPair sp;
  auto got = drivers::can::read_frame(sp.fd[1], 20ms, "pair");
  ASSERT_FALSE(got);
  EXPECT_EQ(got.error().kind, LinkErrorKind::kTimeout);
  EXPECT_EQ(got.error().where, "pair");
}

TEST(CanFrameIo, PeerClosedIsLinkLost) {
  SocketPair sp;
  sp.close_end(0);
  auto got = drivers::can::read_frame(sp.fd[1], 100ms, "pair");
  ASSERT_FALSE(got);
  EXPECT_EQ(got.error().kind, LinkErrorKind::kLinkLost);
  auto w = drivers::can::write_frame(sp.fd[1], j::encode_lockstep({1}), "pair");
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error().kind, LinkErrorKind::kLinkLost);
  EXPECT_NE(w.error().detail.find("send"), std::string::npos);
}

TEST(CanFrameIo, WrongSizedPacketIsProtocolError) {
  SocketPair sp;
  const char junk[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(::send(sp.fd[0], junk, sizeof junk, 0), 5);
  auto got = drivers::can::read_frame(sp.fd[1], 100ms, "pair");
  ASSERT_FALSE(got);
  EXPECT_EQ(got.error().kind, LinkErrorKind::kProtocol);
  EXPECT_NE(got.error().detail.find("got 5 bytes"), std::string::npos);
}

TEST(CanUdp, LoopbackExchangeBetweenNodeAndClient) {
  auto node = drivers::can::open_can_endpoint(udp_uri(0), CanRole::kNode);
  ASSERT_TRUE(node) << node.error().message();
  auto& n = *node.value();
  ASSERT_GT(n.local_port(), 0);
  EXPECT_FALSE(n.has_peer());
  auto early = n.send(j::encode_plant_sample({1e6, 1, 0}));
  ASSERT_FALSE(early);
  EXPECT_NE(early.error().detail.find("no peer yet"), std::string::npos);

  auto client = drivers::can::open_can_endpoint(udp_uri(n.local_port()), CanRole::kClient);
  ASSERT_TRUE(client) << client.error().message();
  auto& c = *client.value();
  ASSERT_TRUE(c.send(j::encode_rig_command({0.25, true, 1})));
  auto at_node = n.receive(200ms);
  ASSERT_TRUE(at_node) << at_node.error().message();
  EXPECT_TRUE(n.has_peer());
  auto cmd = j::decode_rig_command(*at_node);
  ASSERT_TRUE(cmd);
  EXPECT_DOUBLE_EQ(cmd->bias_pct, 0.25);

  for (std::uint16_t k = 2; k <= 4; ++k) ASSERT_TRUE(n.send(j::encode_plant_sample({2e6, k, 1})));
  for (std::uint16_t k = 2; k <= 4; ++k) {
    auto at_client = c.receive(200ms);
    ASSERT_TRUE(at_client) << at_client.error().message();
    EXPECT_EQ(j::decode_plant_sample(*at_client)->counter, k);  // order preserved on loopback
  }
  EXPECT_EQ(c.receive(10ms).error().kind, LinkErrorKind::kTimeout);
}

TEST(CanUdp, AbsentNodeIsLinkLost) {
  int port = 0;
  {
    auto node = drivers::can::open_can_endpoint(udp_uri(0), CanRole::kNode);
    ASSERT_TRUE(node);
    port = node.value()->local_port();
  }  // closed: nothing listens on `port` now
  auto client = drivers::can::open_can_endpoint(udp_uri(port), CanRole::kClient);
  ASSERT_TRUE(client);
  ASSERT_TRUE(client.value()->send(j::encode_lockstep({1})));  // ICMP comes back later
  auto r = client.value()->receive(200ms);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kLinkLost) << r.error().message();
  EXPECT_NE(r.error().detail.find("refused"), std::string::npos) << r.error().detail;
}

TEST(SocketCan, UnavailableIsOneClearError) {
  auto ep = drivers::can::open_socketcan("vcan0");
  if (ep) GTEST_SKIP() << "this host has CAN and vcan0; the unavailable path is not reachable";
  if (ep.error().kind != LinkErrorKind::kUnavailable) {
    FAIL() << "expected kUnavailable, got " << ep.error().message();
  }
  EXPECT_NE(ep.error().detail.find("CAN unavailable on this host"), std::string::npos);
  EXPECT_EQ(ep.error().where, "can+socketcan:vcan0");
  auto via_uri = drivers::can::open_can_endpoint(
      drivers::parse_link_uri("can+socketcan:vcan0").value(), CanRole::kClient);
  ASSERT_FALSE(via_uri);
  EXPECT_EQ(via_uri.error().kind, LinkErrorKind::kUnavailable);
}

TEST(SocketCan, VcanExchange) {
  auto a = drivers::can::open_socketcan("vcan0");
  if (!a) GTEST_SKIP() << "SocketCAN test skipped: " << a.error().message();
  auto b = drivers::can::open_socketcan("vcan0");
  ASSERT_TRUE(b) << b.error().message();
  ASSERT_TRUE(a.value()->send(j::encode_eec1({600.0, 50.0})));
  auto got = b.value()->receive(200ms);
  ASSERT_TRUE(got) << got.error().message();
  EXPECT_DOUBLE_EQ(j::decode_eec1(*got)->speed_rpm, 600.0);
}
