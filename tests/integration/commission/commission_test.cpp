// rig commission --emulate end to end: the MMFM model must match the emulated plant's own
// linearisation within the acceptance tolerances (+-1 dB, +-5 deg over 0.5-5 Hz).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "rig/io/recording.hpp"
#include "tests/integration/commission/run_rig.hpp"

namespace rig::testing {
namespace {

std::string short_profile() {
  return (source_dir() / "tests/integration/commission/short.toml").string();
}

void expect_complete_outputs(const std::filesystem::path& out) {
  for (const char* f : {"recording.csv", "recording.json", "model.json", "sweep.csv", "h1.csv",
                        "report.json", "report.html"}) {
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  }
  const auto rec = io::read_recording(out / "recording.csv");
  EXPECT_GT(rec.rows(), 10000);
  EXPECT_TRUE(rec.has("u") && rec.has("y"));
  const auto report = read_json(out / "report.json");
  EXPECT_EQ(report["exit_code"], 0);
  EXPECT_EQ(report["compare"]["sweep"]["verdict"], "pass");
  EXPECT_LE(report["safety"]["max_abs_deviation_pct"].get<double>(), 3.0);
  EXPECT_TRUE(report["safety"]["trip"].is_null());
}

void run_and_check(const std::string& link_type, std::uint64_t seed) {
  const auto out = fresh_dir(link_type + "-" + std::to_string(seed));
  const int code = run_rig(fmt::format("commission --emulate --preset stornoway --seed {} "
                                       "--link-type {} --test {} --quiet --out {}",
                                       seed, link_type, short_profile(), out.string()),
                           log_beside(out));
  ASSERT_EQ(code, 0) << read_text(log_beside(out));
  expect_complete_outputs(out);
  const TruthError e = error_against_truth(out / "model.json");
  fmt::print("{} seed {}: MMFM vs plant linearisation over 0.5-5 Hz: {:.2f} dB, {:.2f} deg\n",
             link_type, seed, e.max_db, e.max_deg);
  EXPECT_LE(e.max_db, 1.0);
  EXPECT_LE(e.max_deg, 5.0);
}

TEST(Commission, ModbusTcpModelMatchesThePlant) { run_and_check("modbus+tcp", 1); }
TEST(Commission, ModbusTcpSecondSeedMatchesThePlant) { run_and_check("modbus+tcp", 2); }
TEST(Commission, CanUdpModelMatchesThePlant) { run_and_check("can+udp", 3); }
TEST(Commission, ModbusRtuOverPtyModelMatchesThePlant) {
  if (!std::filesystem::exists("/usr/bin/socat")) GTEST_SKIP() << "socat not installed";
  run_and_check("modbus+rtu", 4);
}

TEST(Commission, SameSeedGivesTheSameRecording) {
  std::string first;
  for (int i = 0; i < 2; ++i) {
    const auto out = fresh_dir("repeat-" + std::to_string(i));
    ASSERT_EQ(run_rig(fmt::format("commission --emulate --seed 5 --test {} --quiet --out {}",
                                  short_profile(), out.string()),
                      log_beside(out)),
              0)
        << read_text(log_beside(out));
    const std::string rec = read_text(out / "recording.csv");
    if (i == 0) {
      first = rec;
    } else {
      EXPECT_TRUE(rec == first) << "lockstep runs with one seed must be identical";
    }
  }
}

}  // namespace
}  // namespace rig::testing
