// The CAN GovernorLink over can+udp against a small J1939 node in a thread (the same
// transport and codecs plantsim's CAN node uses).
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

#include "drivers/can/can_link.hpp"
#include "drivers/can/j1939.hpp"
#include "drivers/can/transport.hpp"
#include "drivers/open_link.hpp"

namespace j = drivers::j1939;
using drivers::LinkErrorKind;
using drivers::LinkOptions;
using drivers::can::CanRole;
using namespace std::chrono_literals;

namespace {

// A governor as plantsim's CAN node behaves, in small: every accepted command (0xFF50, TSC1)
// is echoed by 0xFF53 at the next tick. Lockstep: 0xFF52 {n} takes n ticks (EEC1 each), then
// one 0xFF51 and one GTACP. free_run (realtime): one tick per millisecond once contacted, and
// a 0xFF51 at every tick that answered a command. Power follows the applied bias.
class TestNode {
 public:
  TestNode() {
    auto ep = drivers::can::open_can_endpoint(
        drivers::parse_link_uri("can+udp://127.0.0.1:0").value(), CanRole::kNode);
    EXPECT_TRUE(ep) << ep.error().message();
    ep_ = std::move(ep.value());
    thread_ = std::thread([this] { run(); });
  }
  ~TestNode() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    ep_.reset();
  }
  int port() const { return ep_->local_port(); }
  std::vector<j::RigCommand> commands() const {
    std::lock_guard lock(mutex_);
    return commands_;
  }
  int command_errors() const { return command_errors_; }
  std::vector<j::Tsc1> tsc1() const {
    std::lock_guard lock(mutex_);
    return tsc1_;
  }

  std::atomic<bool> freeze_counter{false};
  std::atomic<bool> corrupt{false};
  std::atomic<bool> silent{false};
  std::atomic<bool> no_echo{false};
  std::atomic<bool> free_run{false};
  std::atomic<double> clamp_pct{5.0};  // the governor's clamp on the applied bias

 private:
  void run() {
    while (!stop_) {
      auto f = ep_->receive(free_run ? 1ms : 10ms);
      if (free_run && ep_->has_peer()) {
        const bool answered = tick();
        if (answered) send_sample();
      }
      if (f) take(*f);
    }
  }
  void take(const can_frame& f) {
    if (j::pgn_of(f) == j::kPgnRigCommand) {
      auto c = j::decode_rig_command(f, previous_);  // checks the heartbeat counter
      if (!c) {
        ++command_errors_;
        return;
      }
      previous_ = c->counter;
      std::lock_guard lock(mutex_);
      commands_.push_back(*c);
      bias_pct_ = c->enable ? std::clamp(c->bias_pct, -clamp_pct.load(), clamp_pct.load()) : 0.0;
      pending_echoes_.push_back(c->counter);
    } else if (j::pgn_of(f) == j::kPgnTsc1) {
      std::lock_guard lock(mutex_);
      auto t =
          j::decode_tsc1(f, tsc1_.empty() ? std::nullopt : std::optional(tsc1_.back().counter));
      if (!t) {
        ++command_errors_;
        return;
      }
      tsc1_.push_back(*t);
      pending_echoes_.push_back(t->counter);
    } else if (auto l = j::decode_lockstep(f); l && !silent) {
      for (int k = 0; k < l->ticks; ++k) tick();
      send_sample();
      (void)ep_->send(j::encode_gtacp({power_w(), 0.0}));
    }
  }
  double power_w() const { return 3.5e6 + bias_pct_ * 46.0e3; }
  // One plant tick; true when it answered a command.
  bool tick() {
    if (!freeze_counter) ++counter_;
    (void)ep_->send(j::encode_eec1({600.5, 70.0}));
    std::lock_guard lock(mutex_);
    const bool answered = !pending_echoes_.empty();
    for (auto c : pending_echoes_) {
      if (!no_echo) (void)ep_->send(j::encode_bias_echo({bias_pct_, bias_pct_, counter_, 0x07, c}));
    }
    pending_echoes_.clear();
    return answered;
  }
  void send_sample() {
    can_frame s = j::encode_plant_sample({power_w(), counter_, 0x07});
    if (corrupt) s.data[0] ^= 0x10;
    (void)ep_->send(s);
  }

  std::unique_ptr<drivers::can::CanEndpoint> ep_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::vector<j::RigCommand> commands_;
  std::vector<j::Tsc1> tsc1_;
  std::vector<std::uint8_t> pending_echoes_;
  std::optional<std::uint8_t> previous_;
  std::atomic<int> command_errors_{0};
  double bias_pct_ = 0.0;
  std::uint16_t counter_ = 100;
};

std::unique_ptr<drivers::GovernorLink> connect(const TestNode& node, bool lockstep = true,
                                               const std::string& query = "") {
  LinkOptions o;
  o.lockstep = lockstep;
  o.response_timeout = 200ms;
  o.ramp_rate_pct_per_s = 25.0;
  o.plant_tick = 1ms;
  auto link = drivers::open_link("can+udp://127.0.0.1:" + std::to_string(node.port()) + query, o);
  EXPECT_TRUE(link) << link.error().message();
  auto r = link.value()->configure();
  EXPECT_TRUE(r) << r.error().message();
  return std::move(link.value());
}

}  // namespace

TEST(CanLink, LockstepCycleOverUdp) {
  TestNode node;
  auto link = connect(node);
  ASSERT_TRUE(link->activate());
  ASSERT_TRUE(link->write(0.5));
  ASSERT_TRUE(link->advance(1));
  auto first = link->read();
  ASSERT_TRUE(first) << first.error().message();
  EXPECT_EQ(first->counter, 101);
  EXPECT_DOUBLE_EQ(first->bias_echo_pct, 0.5);
  ASSERT_TRUE(link->write(-1.25));
  ASSERT_TRUE(link->advance(4));
  auto s = link->read();
  ASSERT_TRUE(s) << s.error().message();
  EXPECT_EQ(s->counter, 105);
  EXPECT_DOUBLE_EQ(s->power_kw, 3500.0 - 1.25 * 46.0);
  EXPECT_DOUBLE_EQ(s->speed_rpm, 600.5);
  EXPECT_DOUBLE_EQ(s->bias_echo_pct, -1.25);  // from 0xFF53
  EXPECT_EQ(s->status, 0x07);
  EXPECT_DOUBLE_EQ(s->plant_time_s, 0.105);

  const auto c = node.commands();
  ASSERT_EQ(c.size(), 3u);
  EXPECT_TRUE(c[0].enable);
  EXPECT_DOUBLE_EQ(c[1].bias_pct, 0.5);
  EXPECT_DOUBLE_EQ(c[2].bias_pct, -1.25);
  EXPECT_EQ(node.command_errors(), 0);  // heartbeat counter +1 per frame, checksums good
}

// The echo is what the governor applies, not what was written: a clamping governor shows.
TEST(CanLink, EchoReportsTheClampedBias) {
  TestNode node;
  node.clamp_pct = 2.0;
  auto link = connect(node);
  ASSERT_TRUE(link->activate());
  ASSERT_TRUE(link->write(3.5));
  ASSERT_TRUE(link->advance(2));
  auto s = link->read();
  ASSERT_TRUE(s) << s.error().message();
  EXPECT_DOUBLE_EQ(s->bias_echo_pct, 2.0);
}

TEST(CanLink, MissingEchoIsATimeoutNamingFF53) {
  TestNode node;
  node.no_echo = true;
  auto link = connect(node);
  ASSERT_TRUE(link->activate());
  ASSERT_TRUE(link->advance(1));
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kTimeout);
  EXPECT_NE(s.error().where.find("PGN 0xFF53"), std::string::npos) << s.error().message();
}

// Before activation the link sends 0xFF50 {bias 0, enable 00} so that a governor answering
// commands (and a can+udp node, which cannot send before it has heard the rig) answers reads.
TEST(CanLink, ReadsBeforeActivationSendIdleFrames) {
  TestNode node;
  node.free_run = true;
  auto link = connect(node, /*lockstep=*/false);
  for (int i = 0; i < 3; ++i) {
    auto s = link->read();
    ASSERT_TRUE(s) << "read " << i << ": " << s.error().message();
    EXPECT_DOUBLE_EQ(s->bias_echo_pct, 0.0);
  }
  const auto c = node.commands();
  ASSERT_EQ(c.size(), 3u);  // one idle frame per read
  for (const auto& cmd : c) {
    EXPECT_FALSE(cmd.enable);
    EXPECT_FALSE(cmd.keep_enable);
    EXPECT_DOUBLE_EQ(cmd.bias_pct, 0.0);
  }
  EXPECT_EQ(node.command_errors(), 0);
}

TEST(CanLink, RealtimeReadsReturnNewTicks) {
  TestNode node;
  node.free_run = true;
  auto link = connect(node, /*lockstep=*/false);
  ASSERT_TRUE(link->activate());  // the node learns its peer and starts ticking
  std::optional<std::uint16_t> last;
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(link->write(0.1 * i));
    auto s = link->read();
    ASSERT_TRUE(s) << s.error().message();
    if (last) {
      EXPECT_NE(s->counter, *last);  // every read is a tick not seen before
    }
    EXPECT_NEAR(s->bias_echo_pct, 0.1 * i, 1e-9);  // the answer to this write, not an older one
    last = s->counter;
    std::this_thread::sleep_for(3ms);
  }
  node.freeze_counter = true;
  std::this_thread::sleep_for(5ms);
  // Ticks taken before the freeze may still be queued (more than one on a loaded machine):
  // within a few reads the frozen counter must be reported stale.
  std::optional<drivers::LinkError> stale;
  std::uint16_t moving = 0;
  for (int i = 0; i < 5 && !stale; ++i) {
    ASSERT_TRUE(link->write(0.0));
    auto s = link->read();
    if (s)
      moving = s->counter;
    else
      stale = s.error();
  }
  ASSERT_TRUE(stale) << "counter still moving after 5 reads: " << moving;
  EXPECT_EQ(stale->kind, LinkErrorKind::kStale) << stale->message();
}

TEST(CanLink, DeactivateRampsAndClearsEnable) {
  TestNode node;
  auto link = connect(node);
  ASSERT_TRUE(link->activate());
  ASSERT_TRUE(link->write(1.0));
  ASSERT_TRUE(link->deactivate());
  std::this_thread::sleep_for(20ms);  // let the node take the last datagram
  const auto c = node.commands();
  ASSERT_EQ(c.size(), 2u + 2u + 1u);  // 1.0 % in 0.5 % steps, then disable
  EXPECT_DOUBLE_EQ(c[2].bias_pct, 0.5);
  EXPECT_DOUBLE_EQ(c[3].bias_pct, 0.0);
  EXPECT_TRUE(c[3].enable);
  EXPECT_FALSE(c[4].enable);
  EXPECT_EQ(node.command_errors(), 0);
}

TEST(CanLink, Tsc1CommandsSpeedRequestsAndReleases) {
  TestNode node;
  auto link = connect(node, true, "?command=tsc1&sync_rpm=600");
  ASSERT_TRUE(link->activate());
  ASSERT_TRUE(link->write(1.0));
  ASSERT_TRUE(link->write(-0.5));
  ASSERT_TRUE(link->deactivate());
  std::this_thread::sleep_for(20ms);
  const auto t = node.tsc1();
  ASSERT_GE(t.size(), 4u);
  EXPECT_DOUBLE_EQ(t[0].speed_rpm, 600.0);  // activate: synchronous speed, zero bias
  EXPECT_DOUBLE_EQ(t[1].speed_rpm, 606.0);  // 600 (1 + 1 %)
  EXPECT_DOUBLE_EQ(t[2].speed_rpm, 597.0);
  EXPECT_FALSE(t[2].release);
  EXPECT_TRUE(t.back().release);        // disable: override control mode 00, "no override"
  EXPECT_EQ(node.command_errors(), 0);  // TSC1 counter +1 per frame, checksums good
  EXPECT_TRUE(node.commands().empty());
}

// The TSC1 link says once, at configure(), how coarse its speed requests are.
TEST(CanLink, Tsc1WarnsAboutItsResolution) {
  TestNode node;
  auto tsc1 = connect(node, true, "?command=tsc1&sync_rpm=600");
  const auto w = drivers::link_warnings(*tsc1);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("0.125 rpm = 0.0208 %"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("600 rpm"), std::string::npos) << w[0];
  auto ff50 = connect(node);
  EXPECT_TRUE(drivers::link_warnings(*ff50).empty());
}

TEST(CanLink, CorruptFrameIsChecksumError) {
  TestNode node;
  auto link = connect(node);
  node.corrupt = true;
  ASSERT_TRUE(link->advance(1));
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kChecksum);
  EXPECT_EQ(s.error().where, "PGN 0xFF51");
}

TEST(CanLink, FrozenCounterIsStale) {
  TestNode node;
  auto link = connect(node);
  ASSERT_TRUE(link->advance(1));
  ASSERT_TRUE(link->read());
  node.freeze_counter = true;
  ASSERT_TRUE(link->advance(2));
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kStale) << s.error().message();
}

TEST(CanLink, SilentNodeIsTimeout) {
  TestNode node;
  auto link = connect(node);
  node.silent = true;
  ASSERT_TRUE(link->advance(1));
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kTimeout) << s.error().message();
}

TEST(CanLink, NodeGoneIsLinkLost) {
  TestNode node;
  auto link = connect(node);
  node.stop();
  ASSERT_TRUE(link->write(0.0));  // UDP: the refusal comes back asynchronously
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kLinkLost) << s.error().message();
}

TEST(CanLink, SocketcanUnavailableSurfacesAtConfigure) {
  auto link = drivers::open_link("can+socketcan:vcan0");
  ASSERT_TRUE(link);
  auto r = link.value()->configure();
  if (r) GTEST_SKIP() << "this host has vcan0";
  EXPECT_EQ(r.error().kind, LinkErrorKind::kUnavailable);
  EXPECT_NE(r.error().message().find("CAN unavailable on this host"), std::string::npos);
}
