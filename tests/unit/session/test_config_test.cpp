#include "rig/session/test_config.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "rig/session/phase.hpp"
#include "rig/session/supervisor.hpp"

namespace rig::session {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_test_toml(text, "test.toml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return {};
}

TEST(TestConfig, DefaultsAreValidAndDocumentedValuesHold) {
  const TestConfig c = parse_test_toml("", "test.toml");
  EXPECT_DOUBLE_EQ(c.safety.band_pct, 3.0);
  EXPECT_FALSE(c.safety.allow_band_above_3pct);
  EXPECT_DOUBLE_EQ(c.compare.mag_tol_db, 1.0);
  EXPECT_DOUBLE_EQ(c.compare.phase_tol_deg, 5.0);
  EXPECT_DOUBLE_EQ(c.compare.from_hz, 0.5);
  EXPECT_DOUBLE_EQ(c.compare.to_hz, 5.0);
  EXPECT_EQ(c.excitation.type, ExcitationType::kShaped);
}

// One source of the safety defaults: a test file that leaves [safety] (and the sample rate)
// out gives exactly the supervisor configuration the supervisor has by default. Before,
// SupervisorConfig clamped at 2 % and ramped at 1 %/s while the test file said 5 % and 2 %/s.
TEST(TestConfig, SafetyDefaultsGiveTheSupervisorsOwnDefaults) {
  const SupervisorConfig from_file = supervisor_config_from(parse_test_toml("", "test.toml"));
  const SupervisorConfig own;
  EXPECT_DOUBLE_EQ(from_file.band_fraction, own.band_fraction);
  EXPECT_DOUBLE_EQ(from_file.clamp_pct, own.clamp_pct);
  EXPECT_DOUBLE_EQ(from_file.ramp_rate_pct_per_s, own.ramp_rate_pct_per_s);
  EXPECT_DOUBLE_EQ(from_file.dt_s, own.dt_s);
  EXPECT_DOUBLE_EQ(from_file.backoff.zero_fraction, own.backoff.zero_fraction);
  EXPECT_DOUBLE_EQ(from_file.backoff.plan_fraction, own.backoff.plan_fraction);
  EXPECT_DOUBLE_EQ(from_file.echo.tolerance_pct, own.echo.tolerance_pct);
  EXPECT_EQ(from_file.echo.delay_ticks, own.echo.delay_ticks);
  EXPECT_EQ(from_file.echo.max_bad_ticks, own.echo.max_bad_ticks);
  EXPECT_TRUE(from_file == own) << "some other field differs";
  // And a [safety] value does reach the supervisor.
  const TestConfig c = parse_test_toml("[safety]\nclamp_pct = 3.5\n", "test.toml");
  EXPECT_DOUBLE_EQ(supervisor_config_from(c).clamp_pct, 3.5);
}

TEST(TestConfig, ReadsEverySectionIntoItsField) {
  const TestConfig c = parse_test_toml(R"(
[link]
uri = "modbus+tcp://127.0.0.1:1502?unit=1"
sample_rate_hz = 50
[safety]
band_pct = 2.5
[excitation]
type = "prbs"
seed = 42
[mmfm]
delay_s = 0.06
lags = 128
[sweep]
from_hz = 0.2
to_hz = 8.0
points = 10
)",
                                       "test.toml");
  EXPECT_EQ(c.link.uri, "modbus+tcp://127.0.0.1:1502?unit=1");
  EXPECT_DOUBLE_EQ(c.link.sample_rate_hz, 50.0);
  EXPECT_DOUBLE_EQ(c.safety.band_pct, 2.5);
  EXPECT_EQ(c.excitation.type, ExcitationType::kPrbs);
  EXPECT_EQ(c.excitation.seed, 42u);
  ASSERT_TRUE(c.mmfm.delay_s.has_value());
  EXPECT_DOUBLE_EQ(*c.mmfm.delay_s, 0.06);
  EXPECT_EQ(c.mmfm.lags, 128);
  EXPECT_EQ(c.sweep.points, 10);
}

TEST(TestConfig, UnknownKeyIsNamedWithItsLine) {
  const std::string e = error_of("[excitation]\nbandwith_hz = 4\n");
  EXPECT_NE(e.find("test.toml: excitation.bandwith_hz: unknown key (line 2)"), std::string::npos)
      << e;
  EXPECT_NE(error_of("[exitation]\n").find("exitation"), std::string::npos);
}

TEST(TestConfig, WrongTypeNamesTheKeyAndTheExpectedType) {
  const std::string e = error_of("[mmfm]\nlags = \"many\"\n");
  EXPECT_NE(e.find("mmfm.lags: expected an integer, got a string"), std::string::npos) << e;
  EXPECT_NE(error_of("[safety]\nband_pct = true\n").find("expected a number"), std::string::npos);
  EXPECT_NE(error_of("[excitation]\ntype = \"chirp\"\n").find("excitation.type"),
            std::string::npos);
}

TEST(TestConfig, BandAboveThreePercentNeedsTheOverride) {
  const std::string e = error_of("[safety]\nband_pct = 4.0\n");
  EXPECT_NE(e.find("safety.band_pct = 4"), std::string::npos) << e;
  EXPECT_NE(e.find("allow_band_above_3pct"), std::string::npos) << e;
  const TestConfig c =
      parse_test_toml("[safety]\nband_pct = 4.0\nallow_band_above_3pct = true\n", "t");
  EXPECT_DOUBLE_EQ(c.safety.band_pct, 4.0);
  EXPECT_DOUBLE_EQ(parse_test_toml("[safety]\nband_pct = 1.5\n", "t").safety.band_pct, 1.5);
}

// Every numeric key has an upper bound (docs/test-file.md "Safe ranges"): values a user
// reported as accepted are refused with the key, the value and the bound.
TEST(TestConfig, AbsurdValuesAreRefusedWithTheirBound) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"[safety]\nclamp_pct = 1000\n", "safety.clamp_pct = 1000: must be at most 10"},
      {"[safety]\nramp_pct_per_s = 1e9\n",
       "safety.ramp_pct_per_s = 1000000000: must be at most 10"},
      {"[link]\ntimeout_s = 1e12\n", "link.timeout_s = 1000000000000: must be at most 10"},
      {"[link]\nsample_rate_hz = 1e9\n", "link.sample_rate_hz = 1000000000: must be at most 1000"},
      {"[mmfm]\norder_n = 1000\n", "mmfm.order_n = 1000: must be at most 8"},
      {"[safety]\necho_tolerance_pct = 5\n", "safety.echo_tolerance_pct = 5: must be at most 1"},
      {"[mmfm]\nmin_applied_fraction = 2\n", "mmfm.min_applied_fraction = 2: must be at most 1"},
      {"[safety]\nactivation_timeout_s = 0\n", "safety.activation_timeout_s = 0"},
      {"[steady_state]\nduration_s = nan\n", "steady_state.duration_s = nan"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string e = error_of(text);
    EXPECT_NE(e.find(expected), std::string::npos) << text << " -> " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << "one line: " << e;
  }
  // The bounds themselves are accepted.
  EXPECT_EQ(error_of("[safety]\nclamp_pct = 10\nramp_pct_per_s = 10\n[link]\ntimeout_s = 10\n"
                     "sample_rate_hz = 1000\n[mmfm]\norder_n = 8\norder_m = 0\n"),
            "");
}

TEST(TestConfig, SweepAboveNyquistIsRefused) {
  const std::string e = error_of("[link]\nsample_rate_hz = 20\n[sweep]\nto_hz = 12\n");
  EXPECT_NE(e.find("sweep.to_hz = 12"), std::string::npos) << e;
  EXPECT_NE(e.find("Nyquist"), std::string::npos) << e;
  EXPECT_NE(error_of("[sweep]\nfrom_hz = 3\nto_hz = 2\n").find("sweep.to_hz"), std::string::npos);
}

TEST(TestConfig, SyntaxErrorIsOneLineWithPosition) {
  const std::string e = error_of("[link\n");
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  EXPECT_NE(e.find("test.toml"), std::string::npos) << e;
  EXPECT_NE(e.find("line 1"), std::string::npos) << e;
}

}  // namespace
}  // namespace rig::session
