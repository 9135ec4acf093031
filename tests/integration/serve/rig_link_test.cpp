// The rig's own GovernorLink clients (drivers::open_link) against the plantsim executable: the
// two ends of the register and CAN maps agree, in lockstep, over Modbus TCP and can+udp.
#include <cmath>

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

}  // namespace
}  // namespace plantsim::testing
