// plantsim's CAN node across processes over can+udp (one struct can_frame per datagram), with
// the drivers' endpoint in client role and the J1939 codecs on the rig side.
#include <map>
#include <set>

#include "drivers/can/j1939.hpp"
#include "drivers/can/transport.hpp"
#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

namespace j1939 = drivers::j1939;
using Clock = std::chrono::steady_clock;
using Frames = std::map<std::uint32_t, std::vector<can_frame>>;

std::unique_ptr<drivers::can::CanEndpoint> can_client(int port) {
  auto uri = drivers::parse_link_uri("can+udp://127.0.0.1:" + std::to_string(port));
  EXPECT_TRUE(uri);
  auto ep = drivers::can::open_can_endpoint(uri.value(), drivers::can::CanRole::kClient);
  EXPECT_TRUE(ep) << (ep ? "" : ep.error().message());
  return ep ? std::move(ep.value()) : nullptr;
}

// Frames received within `window`, grouped by PGN.
Frames collect(drivers::can::CanEndpoint& ep, std::chrono::milliseconds window) {
  Frames by_pgn;
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

std::int16_t echo_after_one_tick(drivers::can::CanEndpoint& ep, modbus_t* mb,
                                 Frames* frames = nullptr) {
  send(ep, j1939::encode_lockstep(j1939::Lockstep{1}));
  auto got = collect(ep, 30ms);
  if (frames) *frames = std::move(got);
  return bias_echo_of(read_inputs(mb));
}

Served lockstep_can_and_modbus() {
  return start_served(
      linear_program(),
      {"--modbus", "tcp://127.0.0.1:0", "--can", "udp://127.0.0.1:0", "--clock", "lockstep"}, true,
      true);
}

TEST(CanUdp, LockstepAnswersOneSampleAndOneEchoPerRequest) {
  auto s = lockstep_can_and_modbus();
  ASSERT_GT(s.can_port, 0);
  auto ep = can_client(s.can_port);
  auto mb = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ep && mb);
  send(*ep, command(1.5, 0));
  send(*ep, j1939::encode_lockstep(j1939::Lockstep{25}));
  auto frames = collect(*ep, 200ms);
  // One 0xFF51 for the 25 ticks, carrying the last tick's counter.
  ASSERT_EQ(frames[j1939::kPgnPlantSample].size(), 1u);
  auto sample = j1939::decode_plant_sample(frames[j1939::kPgnPlantSample][0]);
  ASSERT_TRUE(sample);
  EXPECT_EQ(sample->counter, 25);
  EXPECT_NE(sample->status & drivers::kBiasActive, 0);
  // One 0xFF53 for the command, from the tick that applied it (tick 1).
  ASSERT_EQ(frames[j1939::kPgnBiasEcho].size(), 1u);
  auto echo = j1939::decode_bias_echo(frames[j1939::kPgnBiasEcho][0]);
  ASSERT_TRUE(echo) << echo.error().message();
  EXPECT_DOUBLE_EQ(echo->applied_pct, 1.5);
  EXPECT_DOUBLE_EQ(echo->received_pct, 1.5);
  EXPECT_EQ(echo->command_counter, 0);
  EXPECT_EQ(echo->sample_counter, 1);
  EXPECT_NE(echo->status & drivers::kBiasActive, 0);
  // EEC1 at 20 ms of plant time, naming the rig as the controlling device; no GTACP yet.
  ASSERT_EQ(frames[j1939::kPgnEec1].size(), 1u);
  auto eec1 = j1939::decode_eec1(frames[j1939::kPgnEec1][0]);
  ASSERT_TRUE(eec1);
  EXPECT_DOUBLE_EQ(eec1->speed_rpm, 600.0);
  EXPECT_EQ(eec1->controlling_address, j1939::kRigAddress);
  EXPECT_EQ(frames[j1939::kPgnGtacp].size(), 0u);
  EXPECT_EQ(bias_echo_of(read_inputs(mb.get())), 1500);
}

TEST(CanUdp, LockstepCommandsRejectedFramesClampAndHeartbeat) {
  auto s = lockstep_can_and_modbus();
  auto ep = can_client(s.can_port);
  auto mb = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ep && mb);
  send(*ep, command(1.5, 0));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 1500);
  // A bad checksum is ignored.
  can_frame corrupt = command(4.0, 1);
  corrupt.data[7] ^= 0x01;
  send(*ep, corrupt);
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 1500);
  // A counter that skips is ignored, and the next in sequence from it is accepted.
  send(*ep, command(4.0, 9));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 1500);
  send(*ep, command(-2.0, 10));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), -2000);
  // A well-formed command from another source address is not the rig's: ignored.
  send(*ep, j1939::encode_rig_command(j1939::RigCommand{3.0, true, 11}, 0x42));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), -2000);
  // TSC1 speed request 603 rpm at 600 rpm synchronous: the bias 100 (603 - 600) / 600 = 0.5 %.
  send(*ep, j1939::encode_tsc1(j1939::Tsc1{603.0, 0}));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 500);
  // TSC1 "no override" releases: enable cleared.
  send(*ep, j1939::encode_tsc1(j1939::Tsc1{0.0, 1, true}));
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get()), 0);
  // 7.5 % is clamped to the governor's 5 %, and the CAN echo says so.
  send(*ep, command(7.5, 11));
  Frames frames;
  EXPECT_EQ(echo_after_one_tick(*ep, mb.get(), &frames), 5000);
  ASSERT_EQ(frames[j1939::kPgnBiasEcho].size(), 1u);
  auto echo = j1939::decode_bias_echo(frames[j1939::kPgnBiasEcho][0]);
  ASSERT_TRUE(echo);
  EXPECT_DOUBLE_EQ(echo->applied_pct, 5.0);
  EXPECT_DOUBLE_EQ(echo->received_pct, 7.5);
  EXPECT_EQ(echo->command_counter, 11);
  // The counter is the heartbeat: 500 ms of plant time without a frame drops the bias.
  send(*ep, j1939::encode_lockstep(j1939::Lockstep{499}));
  collect(*ep, 100ms);
  EXPECT_EQ(bias_echo_of(read_inputs(mb.get())), 5000);
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
    for (int k = 0; k < 300; ++k) {
      send(*ep, command(k < 90 ? 0.0 : 1.0, static_cast<std::uint8_t>(k & 0x0F)));
      send(*ep, j1939::encode_lockstep(j1939::Lockstep{10}));
      for (;;) {
        auto f = ep->receive(2000ms);
        if (!f) return bytes;
        if (j1939::pgn_of(f.value()) != j1939::kPgnPlantSample) continue;
        bytes.insert(bytes.end(), f.value().data, f.value().data + 8);
        break;
      }
    }
    return bytes;
  };
  const auto a = run("5");
  const auto b = run("5");
  const auto c = run("6");
  ASSERT_EQ(a.size(), 2400u) << program;
  EXPECT_EQ(a, b) << program << ": seed 5 twice";
  EXPECT_NE(a, c) << program << ": seeds 5 and 6";
}

// Realtime, default: each command is answered at the next tick by 0xFF53 and 0xFF51, so the
// bus carries the rig's rate; EEC1 every 20 ms and GTACP every 100 ms of plant time.
TEST(CanUdp, RealtimeAnswersEachCommandEec1Every20msGtacpEvery100ms) {
  auto s = start_served(linear_program(), {"--can", "udp://127.0.0.1:0"}, false, true);
  ASSERT_GT(s.can_port, 0);
  auto ep = can_client(s.can_port);
  ASSERT_TRUE(ep);
  Frames frames;
  for (int k = 0; k < 30; ++k) {
    send(*ep, command(0.01 * k, static_cast<std::uint8_t>(k & 0x0F)));
    for (auto& [pgn, list] : collect(*ep, 10ms)) {
      frames[pgn].insert(frames[pgn].end(), list.begin(), list.end());
    }
  }
  for (auto& [pgn, list] : collect(*ep, 100ms)) {  // silence: nothing more to answer
    frames[pgn].insert(frames[pgn].end(), list.begin(), list.end());
  }
  const auto& samples = frames[j1939::kPgnPlantSample];
  const auto& echoes = frames[j1939::kPgnBiasEcho];
  ASSERT_EQ(echoes.size(), 30u);
  // One sample per answering tick: 30, fewer only if a stalled clock thread met two commands
  // in one tick.
  EXPECT_LE(samples.size(), 30u);
  EXPECT_GE(samples.size(), 28u);
  std::set<std::uint16_t> sample_counters;
  for (const auto& f : samples) {
    auto p = j1939::decode_plant_sample(f);
    ASSERT_TRUE(p);
    sample_counters.insert(p->counter);
  }
  for (int k = 0; k < 30; ++k) {
    auto e = j1939::decode_bias_echo(echoes[k]);
    ASSERT_TRUE(e);
    EXPECT_EQ(e->command_counter, k & 0x0F);
    EXPECT_NEAR(e->applied_pct, 0.01 * k, 1e-9);
    EXPECT_EQ(sample_counters.count(e->sample_counter), 1u) << "echo " << k << " has no sample";
  }
  // EEC1 and GTACP on plant time, from the first command to the end of the window (the
  // samples span it up to the last command, then 100 ms of silence): +-3 at the ends.
  const int span_ticks = *sample_counters.rbegin() - *sample_counters.begin() + 110;
  EXPECT_NEAR(static_cast<double>(frames[j1939::kPgnEec1].size()), span_ticks / 20.0, 3.0);
  EXPECT_NEAR(static_cast<double>(frames[j1939::kPgnGtacp].size()), span_ticks / 100.0, 1.5);
  auto gtacp = j1939::decode_gtacp(frames[j1939::kPgnGtacp].front());
  ASSERT_TRUE(gtacp);
  EXPECT_NEAR(gtacp->real_power_w, 3.5e6, 5e3);  // linear plant at its operating point
}

// --can-sample-period 10ms: 0xFF51 at 100 Hz of plant time whether or not the rig commands.
TEST(CanUdp, RealtimeFixedSamplePeriod) {
  auto s = start_served(linear_program(),
                        {"--can", "udp://127.0.0.1:0", "--can-sample-period", "10ms"}, false, true);
  ASSERT_GT(s.can_port, 0);
  auto ep = can_client(s.can_port);
  ASSERT_TRUE(ep);
  send(*ep, command(0.0, 0));  // names the peer
  auto frames = collect(*ep, 400ms);
  const auto& samples = frames[j1939::kPgnPlantSample];
  ASSERT_GE(samples.size(), 30u);
  EXPECT_LE(samples.size(), 42u);
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const auto a = j1939::decode_plant_sample(samples[i - 1]);
    const auto b = j1939::decode_plant_sample(samples[i]);
    ASSERT_TRUE(a && b);
    EXPECT_EQ(static_cast<std::uint16_t>(b->counter - a->counter), 10);
  }
  EXPECT_EQ(frames[j1939::kPgnBiasEcho].size(), 1u);
}

}  // namespace
}  // namespace plantsim::testing
