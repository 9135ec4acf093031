// The rig's own GovernorLink clients (drivers::open_link) against the plantsim executable: the
// two ends of the register and CAN maps agree, in lockstep, over Modbus TCP and can+udp.
#include <cmath>
#include <thread>

#include "drivers/open_link.hpp"
#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

std::string program() { return real_program_exists() ? real_program() : linear_program(); }

// Activates, runs `cycles` of write(bias) / advance(10) / read(), deactivates. Returns the
// power samples (kW); checks the counter and the echo on the way.
std::vector<double> run_link(const std::string& uri, int cycles) {
  drivers::LinkOptions options;
  options.lockstep = true;
  auto opened = drivers::open_link(uri, options);
  EXPECT_TRUE(opened) << (opened ? "" : opened.error().message());
  if (!opened) return {};
  auto& link = *opened.value();
  std::vector<double> power_kw;
  auto check = [&](const drivers::LinkResult<void>& r, const char* what) {
    EXPECT_TRUE(r) << what << ": " << (r ? "" : r.error().message());
    return r.has_value();
  };
  if (!check(link.configure(), "configure") || !check(link.activate(), "activate")) return {};
  // The very first exchange already advances 10 ticks: over CAN the link must then await the
  // last frame of that burst although it has not seen the plant's counter before.
  std::optional<std::uint16_t> last_counter;
  for (int k = 0; k < cycles; ++k) {
    const double bias_pct = k < cycles / 3 ? 0.0 : 1.0;
    if (!check(link.write(bias_pct), "write") || !check(link.advance(10), "advance")) break;
    auto sample = link.read();
    EXPECT_TRUE(sample) << (sample ? "" : sample.error().message());
    if (!sample) break;
    if (last_counter) {
      EXPECT_EQ(static_cast<std::uint16_t>(sample->counter - *last_counter), 10);
    }
    last_counter = sample->counter;
    EXPECT_NE(sample->status & drivers::kBiasActive, 0);
    // The governor echoes what it applies (Modbus input 5, CAN PGN 0xFF53): the bias written
    // in this exchange, since lockstep applies it before answering.
    EXPECT_DOUBLE_EQ(sample->bias_echo_pct, bias_pct) << uri << " exchange " << k;
    power_kw.push_back(sample->power_kw);
  }
  EXPECT_TRUE(link.deactivate());
  link.close();
  return power_kw;
}

void expect_step_response(const std::vector<double>& p, const char* what) {
  ASSERT_EQ(p.size(), 300u) << what;
  double before = 0, after = 0;
  for (int i = 80; i < 100; ++i) before += p[i] / 20;
  for (int i = 280; i < 300; ++i) after += p[i] / 20;
  // +1 % of 4.6 MW for 2 s: power rises by tens of kW (46 kW at steady state).
  EXPECT_GT(after - before, 20.0) << what;
  EXPECT_LT(after - before, 80.0) << what;
}

TEST(RigLink, ModbusTcpLinkAgainstPlantsim) {
  auto s = start_served(program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  ASSERT_GT(s.modbus_port, 0);
  expect_step_response(
      run_link("modbus+tcp://127.0.0.1:" + std::to_string(s.modbus_port) + "?unit=1", 300),
      "modbus");
}

TEST(RigLink, CanUdpLinkAgainstPlantsim) {
  auto s =
      start_served(program(), {"--can", "udp://127.0.0.1:0", "--clock", "lockstep"}, false, true);
  ASSERT_GT(s.can_port, 0);
  expect_step_response(run_link("can+udp://127.0.0.1:" + std::to_string(s.can_port), 300), "can");
}

// `rig commission --link-type can+udp --clock realtime` failed at once ("timeout at PGN
// 0xFF51"): its steady-state check only reads, and a can+udp node cannot send before it has
// heard the rig. The link now sends 0xFF50 {bias 0, enable 00} on reads before activation,
// which plantsim answers. Here the rig's CAN link does what the commission does: reads at
// 100 Hz before anything is written, then activates and writes.
TEST(RigLink, CanUdpRealtimeReadsBeforeTheFirstWrite) {
  auto s = start_served(linear_program(), {"--can", "udp://127.0.0.1:0", "--clock", "realtime"},
                        false, true);
  ASSERT_GT(s.can_port, 0);
  drivers::LinkOptions options;  // realtime, 200 ms response timeout
  auto opened = drivers::open_link("can+udp://127.0.0.1:" + std::to_string(s.can_port), options);
  ASSERT_TRUE(opened) << opened.error().message();
  auto& link = *opened.value();
  ASSERT_TRUE(link.configure());
  std::optional<std::uint16_t> last;
  for (int k = 0; k < 50; ++k) {  // 0.5 s of steady-state check
    auto sample = link.read();
    ASSERT_TRUE(sample) << "read " << k << ": " << sample.error().message();
    if (last) {
      EXPECT_NE(sample->counter, *last) << "read " << k << " returned an old tick";
    }
    last = sample->counter;
    EXPECT_NE(sample->status & drivers::kRunning, 0);
    EXPECT_EQ(sample->status & drivers::kBiasActive, 0);  // the idle frame changes nothing
    EXPECT_DOUBLE_EQ(sample->bias_echo_pct, 0.0);
    EXPECT_NEAR(sample->power_kw, 3500.0, 5.0);
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(link.activate());
  for (int k = 0; k < 20; ++k) {
    ASSERT_TRUE(link.write(0.75));
    auto sample = link.read();
    ASSERT_TRUE(sample) << "write/read " << k << ": " << sample.error().message();
    EXPECT_DOUBLE_EQ(sample->bias_echo_pct, 0.75);  // the answer to this very write
    EXPECT_NE(sample->status & drivers::kBiasActive, 0);
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_TRUE(link.deactivate());
}

}  // namespace
}  // namespace plantsim::testing
