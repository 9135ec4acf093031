// The plantsim executable with the real generator-set model (build/bin/plantsim): a bias step
// over Modbus in lockstep against the preset's linearised model, seeded determinism, and an
// external client. Skipped when the executable has not been built.
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

namespace map = drivers::modbus_map;

#define REQUIRE_REAL_PLANTSIM() \
  if (!real_program_exists()) GTEST_SKIP() << real_program() << " has not been built"

// Mean electrical power (W) over `exchanges` lockstep exchanges of 10 ticks at `bias`.
double mean_power_w(modbus_t* ctx, std::int16_t bias, int exchanges, std::uint16_t& heartbeat) {
  double sum = 0.0;
  for (int k = 0; k < exchanges; ++k) {
    write_command(ctx, bias, ++heartbeat);
    advance(ctx, 10);
    sum += power_w_of(read_inputs(ctx));
  }
  return sum / exchanges;
}

// DC gain of the preset's model file, kW per % bias: num(0)/den(0).
std::optional<double> model_dc_gain_kw_per_pct() {
  const char* src = std::getenv("RIG_SOURCE_DIR");
  const auto path = std::filesystem::path(src ? src : RIG_SOURCE_DIR_DEFAULT) /
                    "plantsim/presets/stornoway.tf.json";
  std::ifstream in(path);
  if (!in) return std::nullopt;
  const auto model = nlohmann::json::parse(in);
  return model["num"].back().get<double>() / model["den"].back().get<double>();
}

// A +1 % bias step: after 15 s (three times the slowest time constant of the model, about
// 4.9 s) the power change must have the sign of the model's DC gain and be within 15 % of
// its size; averages over 2 s take out the measurement noise.
TEST(RealPlant, BiasStepOverModbusLockstepMatchesModelDcGain) {
  REQUIRE_REAL_PLANTSIM();
  const auto gain = model_dc_gain_kw_per_pct();
  if (!gain) GTEST_SKIP() << "plantsim/presets/stornoway.tf.json not found";
  auto s = start_served(real_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep",
                                         "--preset", "stornoway", "--seed", "11"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  std::uint16_t hb = 0;
  mean_power_w(ctx.get(), 0, 300, hb);  // 3 s at zero bias
  const double p0_w = mean_power_w(ctx.get(), 0, 200, hb);
  mean_power_w(ctx.get(), 1000, 1500, hb);  // +1.000 % for 15 s
  const double p1_w = mean_power_w(ctx.get(), 1000, 200, hb);
  const double dp_kw = (p1_w - p0_w) / 1e3;
  std::printf("seed 11: P0 %.1f kW, +1 %% bias step -> dP %.2f kW (model DC gain %.2f kW/%%)\n",
              p0_w / 1e3, dp_kw, *gain);
  EXPECT_GT(dp_kw * *gain, 0.0) << "sign";
  EXPECT_NEAR(dp_kw, *gain, 0.15 * std::abs(*gain));
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 1000);
}

TEST(RealPlant, LockstepIsDeterministicForASeed) {
  REQUIRE_REAL_PLANTSIM();
  const auto a = lockstep_recording(real_program(), "3");
  const auto b = lockstep_recording(real_program(), "3");
  const auto c = lockstep_recording(real_program(), "4");
  ASSERT_EQ(a.size(), 3000u);
  EXPECT_EQ(a, b) << "seed 3 twice";
  EXPECT_NE(a, c) << "seeds 3 and 4 gave identical bytes: is the plant's noise seeded?";
}

TEST(RealPlant, MbpollReadsTheRealPlant) {
  REQUIRE_REAL_PLANTSIM();
  if (!std::filesystem::exists("/usr/bin/mbpoll")) GTEST_SKIP() << "mbpoll not installed";
  auto s = start_served(real_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  ASSERT_GT(s.modbus_port, 0);
  const std::string base =
      "timeout 10 mbpoll -m tcp -p " + std::to_string(s.modbus_port) + " -a 1 -0 -1 -o 2 ";
  ASSERT_EQ(std::system((base + "-t 4 -r 0 127.0.0.1 500 1 1 >/dev/null").c_str()), 0);
  ASSERT_EQ(std::system((base + "-t 4 -r 100 127.0.0.1 100 >/dev/null").c_str()), 0);
  FILE* pipe = popen((base + "-t 3:int -B -r 0 -c 1 127.0.0.1").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) out += buf;
  pclose(pipe);
  // mbpoll's 32-bit big-endian view of registers 0-1 is the power in W: about 3.5 MW.
  const auto at = out.find("[0]:");
  ASSERT_NE(at, std::string::npos) << out;
  const double power_w = std::stod(out.substr(at + 4));
  EXPECT_NEAR(power_w, 3.5e6, 0.1e6) << out;
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  const auto r = read_inputs(ctx.get());
  EXPECT_EQ(bias_echo_of(r), 500);
  EXPECT_EQ(r[map::kInCounter], 100);
  EXPECT_NEAR(r[map::kInFreq] * map::kFreqHzPerBit, 50.0, 0.5);
  EXPECT_NEAR(r[map::kInSpeed] * map::kSpeedRpmPerBit, 600.0, 6.0);
}

}  // namespace
}  // namespace plantsim::testing
