// plantsim's CAN node across processes over can+udp (one struct can_frame per datagram), with
// the drivers' endpoint in client role and the J1939 codecs on the rig side.
#include <map>

#include "drivers/can/j1939.hpp"
#include "drivers/can/transport.hpp"
#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

namespace j1939 = drivers::j1939;
using Clock = std::chrono::steady_clock;

std::unique_ptr<drivers::can::CanEndpoint> can_client(int port) {
  auto uri = drivers::parse_link_uri("can+udp://127.0.0.1:" + std::to_string(port));
  EXPECT_TRUE(uri);
  auto ep = drivers::can::open_can_endpoint(uri.value(), drivers::can::CanRole::kClient);
  EXPECT_TRUE(ep) << (ep ? "" : ep.error().message());
  return ep ? std::move(ep.value()) : nullptr;
}

// Frames received within `window`, grouped by PGN.
std::map<std::uint32_t, std::vector<can_frame>> collect(drivers::can::CanEndpoint& ep,
                                                        std::chrono::milliseconds window) {
  std::map<std::uint32_t, std::vector<can_frame>> by_pgn;
  const auto end = Clock::now() + window;
  while (Clock::now() < end) {
    auto f = ep.receive(std::chrono::milliseconds(10));
    if (f) by_pgn[j1939::pgn_of(f.value())].push_back(f.value());
  }
  return by_pgn;
}

void send(drivers::can::CanEndpoint& ep, const can_frame& f) {
  auto r = ep.send(f);
  EXPECT_TRUE(r) << (r ? "" : r.error().message());
}

can_frame command(double bias_pct, std::uint8_t counter) {
  return j1939::encode_rig_command(j1939::RigCommand{bias_pct, true, counter});
}

std::int16_t echo_after_one_tick(drivers::can::CanEndpoint& ep, modbus_t* mb) {
  send(ep, j1939::encode_lockstep(j1939::Lockstep{1}));
  collect(ep, 30ms);
  return bias_echo_of(read_inputs(mb));
}

TEST(CanUdp, LockstepFramesCommandsAndRejectedFrames) {
  auto s = start_served(
      linear_program(),
      {"--modbus", "tcp://127.0.0.1:0", "--can", "udp://127.0.0.1:0", "--clock", "lockstep"}, true,
      true);
  ASSERT_GT(s.can_port, 0);
  auto ep = can_client(s.can_port);
  auto mb = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ep && mb);
  send(*ep, command(1.5, 0));
  send(*ep, j1939::encode_lockstep(j1939::Lockstep{25}));
  auto frames = collect(*ep, 200ms);
  // One 0xFF51 per tick with the sample counter, EEC1 at 20 ms, no GTACP before 100 ms.
  ASSERT_EQ(frames[j1939::kPgnPlantSample].size(), 25u);
  for (std::size_t i = 0; i < 25; ++i) {
    auto sample = j1939::decode_plant_sample(frames[j1939::kPgnPlantSample][i]);
    ASSERT_TRUE(sample);
    EXPECT_EQ(sample->counter, i + 1);
    EXPECT_NE(sample->status & drivers::kBiasActive, 0);
  }
  ASSERT_EQ(frames[j1939::kPgnEec1].size(), 1u);
  auto eec1 = j1939::decode_eec1(frames[j1939::kPgnEec1][0]);
  ASSERT_TRUE(eec1);
  EXPECT_DOUBLE_EQ(eec1->speed_rpm, 600.0);
  EXPECT_EQ(frames[j1939::kPgnGtacp].size(), 0u);
  EXPECT_EQ(bias_echo_of(read_inputs(mb.get())), 1500);

  // A bad checksum is ignored.
  can_frame corrupt = command(5.0, 1);
  corrupt.data[7] ^= 0x01;
  send(*ep, corrupt);
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 1500);
  // A counter that skips is ignored, and the next in sequence from it is accepted.
  send(*ep, command(4.0, 9));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 1500);
  send(*ep, command(-2.0, 10));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), -2000);
  // TSC1 speed request 603 rpm at 600 rpm synchronous: the bias 100 (603 - 600) / 600 = 0.5 %.
  send(*ep, j1939::encode_tsc1(j1939::Tsc1{603.0, 0}));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 500);
  send(*ep, command(-2.0, 11));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), -2000);
  // The counter is the heartbeat: 500 ms of plant time without a frame drops the bias.
  send(*ep, j1939::encode_lockstep(j1939::Lockstep{499}));
  collect(*ep, 100ms);
  EXPECT_EQ(bias_echo_of(read_inputs(mb.get())), -2000);
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 0);
}

// The same seed and the same frames give the same bytes back (the real plant when built).
TEST(CanUdp, LockstepIsDeterministicForASeed) {
  const std::string program = real_program_exists() ? real_program() : linear_program();
  auto run = [&](const std::string& seed) {
    std::vector<std::uint8_t> bytes;
    auto s =
        start_served(program, {"--can", "udp://127.0.0.1:0", "--clock", "lockstep", "--seed", seed},
                     false, true);
    auto ep = can_client(s.can_port);
    if (!ep) return bytes;
    for (int k = 0; k < 100; ++k) {
      send(*ep, command(k < 30 ? 0.0 : 1.0, static_cast<std::uint8_t>(k & 0x0F)));
      send(*ep, j1939::encode_lockstep(j1939::Lockstep{10}));
      for (int got = 0; got < 10;) {
        auto f = ep->receive(2000ms);
        if (!f) return bytes;
        if (j1939::pgn_of(f.value()) != j1939::kPgnPlantSample) continue;
        bytes.insert(bytes.end(), f.value().data, f.value().data + 8);
        ++got;
      }
    }
    return bytes;
  };
  const auto a = run("5");
  const auto b = run("5");
  const auto c = run("6");
  ASSERT_EQ(a.size(), 8000u) << program;
  EXPECT_EQ(a, b) << program << ": seed 5 twice";
  EXPECT_NE(a, c) << program << ": seeds 5 and 6";
}

TEST(CanUdp, RealtimeSendsSampleEveryTickEec1Every20msGtacpEvery100ms) {
  auto s = start_served(linear_program(), {"--can", "udp://127.0.0.1:0"}, false, true);
  ASSERT_GT(s.can_port, 0);
  auto ep = can_client(s.can_port);
  ASSERT_TRUE(ep);
  send(*ep, command(0.0, 0));
  auto frames = collect(*ep, 400ms);
  const auto& samples = frames[j1939::kPgnPlantSample];
  ASSERT_GT(samples.size(), 200u);
  const auto first = j1939::decode_plant_sample(samples.front());
  const auto last = j1939::decode_plant_sample(samples.back());
  ASSERT_TRUE(first && last);
  const int span_ticks = static_cast<std::uint16_t>(last->counter - first->counter);
  EXPECT_EQ(span_ticks + 1, static_cast<int>(samples.size())) << "a sample frame was lost";
  // Over span_ticks of 1 ms: span/20 EEC1 and span/100 GTACP frames, +-1 at the window ends.
  EXPECT_NEAR(static_cast<double>(frames[j1939::kPgnEec1].size()), span_ticks / 20.0, 1.0);
  EXPECT_NEAR(static_cast<double>(frames[j1939::kPgnGtacp].size()), span_ticks / 100.0, 1.0);
  auto gtacp = j1939::decode_gtacp(frames[j1939::kPgnGtacp].front());
  ASSERT_TRUE(gtacp);
  EXPECT_NEAR(gtacp->real_power_w, 3.5e6, 5e3);  // linear plant at its operating point
}

}  // namespace
}  // namespace plantsim::testing
