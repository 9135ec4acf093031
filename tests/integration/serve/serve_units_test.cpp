// The pure pieces of the serving layer, in process: request decoding, input-register encoding,
// endpoint and tick parsing, the jitter histogram, and the governor rules on a linear plant.
#include <gtest/gtest.h>

#include "drivers/can/j1939.hpp"
#include "drivers/governor_link.hpp"
#include "drivers/modbus/modbus_server.hpp"
#include "plantsim/serve/can_node.hpp"
#include "plantsim/serve/endpoint.hpp"
#include "plantsim/serve/governor.hpp"
#include "plantsim/serve/modbus_node.hpp"
#include "plantsim/serve/realtime_clock.hpp"
#include "tests/integration/serve/linear_plant.hpp"

namespace plantsim::testing {
namespace {

using namespace std::chrono_literals;

TEST(ServeUnits, DecodesWriteMultipleRequest) {
  // MBAP (tid 7, proto 0, len 13, unit 1), FC16 at 0, 3 registers, 6 bytes: -5, 9, 1.
  std::array<std::uint8_t, MODBUS_MAX_ADU_LENGTH> adu{0, 7, 0, 0,    0,    13, 1, 0x10, 0, 0,
                                                      0, 3, 6, 0xFF, 0xFB, 0,  9, 0,    1};
  const auto r = drivers::decode_request(adu.data(), 19, 7, 101);
  EXPECT_EQ(r.unit, 1);
  EXPECT_EQ(r.function, 0x10);
  EXPECT_EQ(r.write_address, 0);
  ASSERT_EQ(r.values.size(), 3u);
  EXPECT_EQ(static_cast<std::int16_t>(r.values[0]), -5);
  EXPECT_TRUE(r.write_in_range);
  // The same claiming 3 registers at 99: out of range, nothing to act on.
  adu[9] = 99;
  EXPECT_FALSE(drivers::decode_request(adu.data(), 19, 7, 101).write_in_range);
  // A truncated frame (count says 3, only 1 value present) carries no values.
  EXPECT_FALSE(drivers::decode_request(adu.data(), 15, 7, 101).is_write());
}

TEST(ServeUnits, EncodesInputRegistersWithSaturation) {
  serve::GovernorSnapshot s;
  s.measurement.power_w = -1.5e6;
  s.measurement.speed_rpm = 600.04;
  s.measurement.freq_hz = 50.0126;
  s.measurement.voltage_v = 1e9;  // saturates at 65535
  s.bias_applied_pct = -40.0;     // saturates at -32.768 %
  s.status = 0x15;
  s.ticks = 70000;
  s.plant_time = 70000ms;
  std::uint16_t r[10];
  serve::encode_input_registers(s, r);
  EXPECT_EQ(static_cast<std::int32_t>((std::uint32_t{r[0]} << 16) | r[1]), -1500000);
  EXPECT_EQ(r[2], 6000);
  EXPECT_EQ(r[3], 50013);  // 0.001 Hz per bit, rounded
  EXPECT_EQ(r[4], 65535);
  EXPECT_EQ(static_cast<std::int16_t>(r[5]), -32768);
  EXPECT_EQ(r[6], 0x15);
  EXPECT_EQ((std::uint32_t{r[7]} << 16) | r[8], 70000u);
  EXPECT_EQ(r[9], 70000 - 65536);
}

TEST(ServeUnits, ParsesTicksAndEndpoints) {
  EXPECT_EQ(serve::parse_tick("1ms"), 1ms);
  EXPECT_EQ(serve::parse_tick("500us"), 500us);
  EXPECT_EQ(serve::parse_tick("0.002s"), 2ms);
  EXPECT_THROW(serve::parse_tick("2"), ConfigError);
  EXPECT_THROW(serve::parse_tick("5s"), ConfigError);
  const auto m = serve::parse_modbus_endpoint("rtu:/dev/ttyS3?baud=9600&parity=E");
  EXPECT_EQ(m.scheme, drivers::LinkScheme::kModbusRtu);
  EXPECT_EQ(m.device, "/dev/ttyS3");
  EXPECT_EQ(m.baud, 9600);
  EXPECT_EQ(m.parity, 'E');
  EXPECT_EQ(serve::parse_can_endpoint("udp://127.0.0.1:0").port, 0);
  EXPECT_THROW(serve::parse_modbus_endpoint("udp://127.0.0.1:0"), ConfigError);
  EXPECT_THROW(serve::parse_can_endpoint("rtu:/dev/ttyS0"), ConfigError);
}

TEST(ServeUnits, JitterPercentilesFromHistogram) {
  serve::JitterHistogram h;
  for (int i = 0; i < 98; ++i) h.add(10us, 1ms);
  h.add(500us, 1ms);
  h.add(3ms, 1ms);
  const auto s = h.stats();
  EXPECT_EQ(s.ticks, 100u);
  EXPECT_DOUBLE_EQ(s.p50_us, 11.0);  // upper edge of the 10-11 us bin
  EXPECT_DOUBLE_EQ(s.p99_us, 501.0);
  EXPECT_DOUBLE_EQ(s.max_us, 3000.0);
  EXPECT_EQ(s.late_over_1_tick, 1u);
}

// Heartbeats from two transports are independent; either keeps the bias alive.
TEST(ServeUnits, GovernorHeartbeatPerSource) {
  LinearPlantOptions o;
  serve::Governor g(std::make_unique<LinearPlant>(o));
  EXPECT_TRUE(g.snapshot().heartbeat_lost);
  g.set_bias_pct(2.0);
  g.set_enable(true);
  g.heartbeat(serve::CommandSource::kModbus, 5);
  g.advance(400);
  g.heartbeat(serve::CommandSource::kCan, 5);  // first token from CAN counts as a change
  g.advance(400);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_applied_pct, 2.0);
  g.heartbeat(serve::CommandSource::kModbus, 5);  // unchanged: not a heartbeat
  g.advance(101);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_applied_pct, 0.0);
  EXPECT_NE(g.snapshot().status & drivers::kHeartbeatLost, 0);
  g.set_enable(false);
  g.heartbeat(serve::CommandSource::kModbus, 6);
  g.advance(1);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_applied_pct, 0.0);  // alive but disabled
  EXPECT_EQ(g.snapshot().status & drivers::kHeartbeatLost, 0);
}

// The governor's clamp (the plant's external_bias_limit_pct) bounds what is applied and
// echoed, whatever the transport carried; disabled is still zero.
TEST(ServeUnits, GovernorClampsTheAppliedBias) {
  LinearPlantOptions o;
  o.bias_limit_pct = 2.5;
  serve::Governor g(std::make_unique<LinearPlant>(o));
  g.set_enable(true);
  g.heartbeat(serve::CommandSource::kModbus, 1);
  g.set_bias_pct(4.0);
  g.advance(1);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_applied_pct, 2.5);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_requested_pct, 4.0);
  g.set_bias_pct(-30.0);
  g.advance(1);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_applied_pct, -2.5);
  g.set_bias_pct(1.25);
  g.advance(1);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_applied_pct, 1.25);
  EXPECT_EQ(Plant::kDefaultExternalBiasLimitPct, 5.0);
}

// The CAN node takes commands only from its configured rig address; enable state 11 keeps the
// enable as it was.
TEST(ServeUnits, CanNodeAcceptsCommandsOnlyFromTheRigAddress) {
  namespace j1939 = drivers::j1939;
  serve::Governor g(std::make_unique<LinearPlant>(LinearPlantOptions{}));
  serve::CanNodeOptions options;
  options.rig_address = 0x42;
  auto node = serve::CanNode::open(serve::parse_can_endpoint("udp://127.0.0.1:0"), g,
                                   serve::ClockMode::kLockstep, options);
  ASSERT_TRUE(node) << node.error().message();
  auto& n = *node.value();
  n.handle(j1939::encode_rig_command({1.0, true, 0}));  // from 0xF9: not the rig here
  EXPECT_DOUBLE_EQ(g.snapshot().bias_requested_pct, 0.0);
  EXPECT_FALSE(g.snapshot().enabled);
  EXPECT_EQ(n.counters().wrong_source, 1u);
  n.handle(j1939::encode_lockstep({5}, 0xF9));
  EXPECT_EQ(g.snapshot().ticks, 0u);
  EXPECT_EQ(n.counters().wrong_source, 2u);
  n.handle(j1939::encode_rig_command({1.0, true, 0}, 0x42));
  EXPECT_DOUBLE_EQ(g.snapshot().bias_requested_pct, 1.0);
  EXPECT_TRUE(g.snapshot().enabled);
  n.handle(j1939::encode_rig_command({2.0, false, 1, /*keep_enable=*/true}, 0x42));
  EXPECT_DOUBLE_EQ(g.snapshot().bias_requested_pct, 2.0);
  EXPECT_TRUE(g.snapshot().enabled);  // "don't care" kept it
  n.handle(j1939::encode_lockstep({5}, 0x42));
  EXPECT_EQ(g.snapshot().ticks, 5u);
  EXPECT_DOUBLE_EQ(g.snapshot().bias_applied_pct, 2.0);
  EXPECT_EQ(n.counters().accepted, 3u);
}

}  // namespace
}  // namespace plantsim::testing
