// plantsim's CAN node on SocketCAN (vcan0). Runs where the kernel has CAN and a vcan0
// interface (`ip link add vcan0 type vcan && ip link set vcan0 up`); otherwise skipped with
// the reason the transport gave.
#include "drivers/can/j1939.hpp"
#include "drivers/can/transport.hpp"
#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

namespace j1939 = drivers::j1939;

TEST(SocketCan, LockstepExchangeOnVcan0) {
  auto probe = drivers::can::open_socketcan("vcan0");
  if (!probe) GTEST_SKIP() << probe.error().message();
  auto s = start_served(linear_program(), {"--can", "socketcan:vcan0", "--clock", "lockstep"},
                        false, true);
  ASSERT_TRUE(s.process);
  auto& bus = *probe.value();
  ASSERT_TRUE(bus.send(j1939::encode_rig_command(j1939::RigCommand{1.0, true, 0})));
  ASSERT_TRUE(bus.send(j1939::encode_lockstep(j1939::Lockstep{5})));
  // Lockstep: one 0xFF51 for the 5 ticks, carrying the last tick's counter.
  std::optional<j1939::PlantSample> sample;
  const auto end = std::chrono::steady_clock::now() + 2s;
  while (!sample && std::chrono::steady_clock::now() < end) {
    auto f = bus.receive(100ms);
    if (f && j1939::pgn_of(f.value()) == j1939::kPgnPlantSample) {
      auto decoded = j1939::decode_plant_sample(f.value());
      ASSERT_TRUE(decoded);
      sample = decoded.value();
    }
  }
  ASSERT_TRUE(sample) << "no 0xFF51 on vcan0";
  EXPECT_EQ(sample->counter, 5);
}

}  // namespace
}  // namespace plantsim::testing
