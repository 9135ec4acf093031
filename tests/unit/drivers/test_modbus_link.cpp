// The Modbus GovernorLink against a real libmodbus TCP server on 127.0.0.1.
#include <gtest/gtest.h>
#include <modbus.h>

#include <chrono>
#include <thread>

#include "drivers/modbus/modbus_link.hpp"
#include "drivers/modbus/register_map.hpp"
#include "drivers/open_link.hpp"
#include "modbus_test_server.hpp"

using drivers::LinkErrorKind;
using drivers::LinkOptions;
using drivers::testing::ModbusTestServer;
using namespace std::chrono_literals;

namespace {

std::unique_ptr<drivers::GovernorLink> connect(const ModbusTestServer& server,
                                               LinkOptions options) {
  auto link = drivers::open_link(
      "modbus+tcp://127.0.0.1:" + std::to_string(server.port()) + "?unit=1", options);
  EXPECT_TRUE(link) << link.error().message();
  auto r = link.value()->configure();
  EXPECT_TRUE(r) << r.error().message();
  return std::move(link.value());
}

LinkOptions lockstep_options() {
  LinkOptions o;
  o.lockstep = true;
  o.response_timeout = 200ms;
  o.ramp_rate_pct_per_s = 25.0;  // 0.5 % per 20 ms step
  return o;
}

}  // namespace

TEST(ModbusLink, LockstepCycleWritesBiasHeartbeatAndReadsSample) {
  ModbusTestServer server(/*lockstep=*/true);
  auto link = connect(server, lockstep_options());
  ASSERT_TRUE(link->activate());
  ASSERT_TRUE(link->write(1.2345));
  ASSERT_TRUE(link->advance(1));
  auto first = link->read();
  ASSERT_TRUE(first) << first.error().message();
  ASSERT_TRUE(link->write(1.2345));
  ASSERT_TRUE(link->advance(5));
  auto s = link->read();
  ASSERT_TRUE(s) << s.error().message();
  EXPECT_EQ(s->counter, first->counter + 5);
  // raw bias 1235 -> P = 3.5 MW + 1.235 % * 46 kW/%
  EXPECT_DOUBLE_EQ(s->power_kw, 3500.0 + 1.235 * 46.0);
  EXPECT_DOUBLE_EQ(s->bias_echo_pct, 1.235);
  EXPECT_DOUBLE_EQ(s->speed_rpm, 600.0);
  EXPECT_DOUBLE_EQ(s->freq_hz, 50.0);
  EXPECT_DOUBLE_EQ(s->voltage_v, 11000.0);
  EXPECT_DOUBLE_EQ(s->plant_time_s, s->counter / 1000.0);
  EXPECT_EQ(s->status, drivers::kRunning | drivers::kBreakerClosed | drivers::kBiasActive);

  const auto w = server.writes();
  ASSERT_EQ(w.size(), 3u);  // activate + two writes
  EXPECT_EQ(w[0].control, drivers::modbus_map::kControlEnableBias);
  EXPECT_EQ(w[0].bias_raw, 0);
  for (std::size_t i = 1; i < w.size(); ++i) {
    EXPECT_EQ(w[i].bias_raw, 1235);
    EXPECT_EQ(w[i].heartbeat, static_cast<std::uint16_t>(w[i - 1].heartbeat + 1));
  }
  link->close();
}

TEST(ModbusLink, DeactivateRampsBiasToZeroThenClearsEnable) {
  ModbusTestServer server(true);
  auto link = connect(server, lockstep_options());
  ASSERT_TRUE(link->activate());
  ASSERT_TRUE(link->write(2.0));
  ASSERT_TRUE(link->deactivate());
  const auto w = server.writes();
  // activate, write 2.0, then 4 ramp steps of 0.5 % (2.0 / (25 %/s * 20 ms)), then disable.
  ASSERT_EQ(w.size(), 2u + 4u + 1u);
  const std::int16_t expected[] = {1500, 1000, 500, 0};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(w[2 + i].bias_raw, expected[i]);
    EXPECT_EQ(w[2 + i].control, drivers::modbus_map::kControlEnableBias);
  }
  EXPECT_EQ(w.back().bias_raw, 0);
  EXPECT_EQ(w.back().control, 0);
  for (std::size_t i = 1; i < w.size(); ++i) {
    EXPECT_EQ(w[i].heartbeat, static_cast<std::uint16_t>(w[i - 1].heartbeat + 1));
  }
}

TEST(ModbusLink, BiasQuantisedAndClamped) {
  ModbusTestServer server(true);
  auto link = connect(server, lockstep_options());
  for (double b : {100.0, -100.0, 0.0004, -0.0006}) ASSERT_TRUE(link->write(b));
  const auto w = server.writes();
  ASSERT_EQ(w.size(), 4u);
  EXPECT_EQ(w[0].bias_raw, 32767);
  EXPECT_EQ(w[1].bias_raw, -32768);
  EXPECT_EQ(w[2].bias_raw, 0);
  EXPECT_EQ(w[3].bias_raw, -1);
}

TEST(ModbusLink, SlowServerIsTimeout) {
  ModbusTestServer server(false);
  LinkOptions o;
  o.response_timeout = 50ms;
  auto link = connect(server, o);
  server.reply_delay_ms = 150;
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kTimeout) << s.error().message();
  EXPECT_EQ(s.error().where, "input 0-9");
  auto w = link->write(0.1);
  ASSERT_FALSE(w);
  EXPECT_EQ(w.error().kind, LinkErrorKind::kTimeout) << w.error().message();
  EXPECT_EQ(w.error().where, "holding 0-1");
  server.reply_delay_ms = 0;
}

TEST(ModbusLink, IllegalAddressIsModbusException) {
  ModbusTestServer server(false, /*input_count=*/5);
  auto link = connect(server, LinkOptions{});
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kModbusException);
  EXPECT_EQ(s.error().where, "input 0-9");
  EXPECT_NE(s.error().detail.find("exception 2"), std::string::npos) << s.error().detail;
  EXPECT_NE(s.error().message().find("modbus exception at input 0-9: "), std::string::npos);
}

TEST(ModbusLink, FrozenCounterIsStaleInRealtime) {
  ModbusTestServer server(false);
  LinkOptions o;
  o.stale_timeout = 30ms;
  auto link = connect(server, o);
  auto a = link->read();
  ASSERT_TRUE(a) << a.error().message();
  auto b = link->read();
  ASSERT_TRUE(b) << b.error().message();
  EXPECT_EQ(b->counter, a->counter + 1);  // the realtime test plant ticks between reads
  server.freeze_counter = true;
  ASSERT_TRUE(link->read());  // one repeat is fine: the rig may poll faster than the plant
  std::this_thread::sleep_for(60ms);
  auto c = link->read();
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().kind, LinkErrorKind::kStale);
  EXPECT_EQ(c.error().where, "input 9");
}

TEST(ModbusLink, FrozenCounterIsStaleAfterAdvance) {
  ModbusTestServer server(true);
  auto link = connect(server, lockstep_options());
  ASSERT_TRUE(link->advance(1));
  ASSERT_TRUE(link->read());
  server.freeze_counter = true;
  ASSERT_TRUE(link->advance(3));
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kStale);
  EXPECT_NE(s.error().detail.find("3 tick(s)"), std::string::npos) << s.error().detail;
}

TEST(ModbusLink, ServerClosingIsLinkLost) {
  ModbusTestServer server(false);
  auto link = connect(server, LinkOptions{});
  server.close_after_requests = 1;
  ASSERT_TRUE(link->read());
  auto s = link->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kLinkLost) << s.error().message();
}

TEST(ModbusLink, NoServerIsLinkLostAtConfigure) {
  int port = 0;
  { port = ModbusTestServer(false).port(); }  // nothing listens there any more
  auto link = drivers::open_link("modbus+tcp://127.0.0.1:" + std::to_string(port));
  ASSERT_TRUE(link);
  auto r = link.value()->configure();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kLinkLost);
  EXPECT_NE(r.error().detail.find("refused"), std::string::npos) << r.error().detail;
}

TEST(ModbusLink, CallsBeforeConfigureAreConfigErrors) {
  auto link = drivers::open_link("modbus+tcp://127.0.0.1:1");
  ASSERT_TRUE(link);
  EXPECT_EQ(link.value()->read().error().kind, LinkErrorKind::kConfig);
  EXPECT_EQ(link.value()->write(0.0).error().kind, LinkErrorKind::kConfig);
  auto bad = drivers::open_link("modbus+tcp://127.0.0.1");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().kind, LinkErrorKind::kConfig);
}

TEST(ModbusError, OneTranslationOfLibmodbusErrno) {
  EXPECT_EQ(drivers::modbus_error(ETIMEDOUT, "x").kind, LinkErrorKind::kTimeout);
  EXPECT_EQ(drivers::modbus_error(EMBXSBUSY, "x").kind, LinkErrorKind::kModbusException);
  EXPECT_EQ(drivers::modbus_error(EMBBADCRC, "x").kind, LinkErrorKind::kChecksum);
  EXPECT_EQ(drivers::modbus_error(EMBBADSLAVE, "x").kind, LinkErrorKind::kProtocol);
  EXPECT_EQ(drivers::modbus_error(ECONNRESET, "x").kind, LinkErrorKind::kLinkLost);
}
