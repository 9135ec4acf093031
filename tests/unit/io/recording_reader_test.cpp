#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>

#include "rig/io/recording.hpp"
#include "test_files.hpp"

namespace rig::io {
namespace {

using testing::scratch_dir;
using testing::write_text;

TEST(RecordingReader, MatlabQuirksQuotedHeaderTrailingCommaScalarColumnBlankEnd) {
  const std::string text =
      "\"uEst\",\"yEst\",\"Ts\",\n"
      "3.25,5.2,4,\n"
      "3.5,5.25,,\n"
      "-1e-3,+6,,\n"
      "\n";
  const Recording rec = parse_recording(text, "tanks.csv");
  ASSERT_EQ(rec.names, (std::vector<std::string>{"uEst", "yEst"}));
  EXPECT_EQ(rec.rows(), 3);
  EXPECT_DOUBLE_EQ(rec.column("uEst")[2], -1e-3);
  EXPECT_DOUBLE_EQ(rec.column("yEst")[2], 6.0);
  ASSERT_EQ(rec.scalars.count("Ts"), 1u);
  EXPECT_DOUBLE_EQ(rec.scalars.at("Ts"), 4.0);
  EXPECT_DOUBLE_EQ(rec.dt_s, 4.0);
  EXPECT_EQ(rec.sampling.dt_source, "scalar column Ts");
  EXPECT_TRUE(rec.warnings.empty());
}

TEST(RecordingReader, ScalarFsColumnGivesSamplePeriod) {
  const Recording rec = parse_recording("u,y,fs\n1,2,50\n2,3,\n3,4,\n", "wh.csv");
  EXPECT_DOUBLE_EQ(rec.dt_s, 0.02);
}

TEST(RecordingReader, HeaderlessWhitespaceDatNamesColumnsByOneBasedIndex) {
  const std::string text = "   6.41\t   4.76\t\n   3.41\t   4.77\t\n   6.41\t   4.84\t\n";
  ReadOptions options;
  options.dt_s = 0.08;
  const Recording rec = parse_recording(text, "dryer.dat", options);
  EXPECT_FALSE(rec.has_header);
  ASSERT_EQ(rec.names, (std::vector<std::string>{"1", "2"}));
  EXPECT_DOUBLE_EQ(rec.column("2")[2], 4.84);
  EXPECT_DOUBLE_EQ(rec.dt_s, 0.08);
}

TEST(RecordingReader, SelectsColumnsByNameOrIndexAndIgnoresOthers) {
  const std::string text = "t,status,u,y\n0,OK,1,2\n0.5,TRIP,3,4\n1.0,OK,5,6\n";
  ReadOptions options;
  options.columns = {"y", "3"};  // by name, and column 3 = u
  const Recording rec = parse_recording(text, "rec.csv", options);
  ASSERT_EQ(rec.names, (std::vector<std::string>{"y", "u"}));
  EXPECT_DOUBLE_EQ(rec.column("u")[1], 3.0);
  ASSERT_TRUE(rec.time_s.has_value());
  EXPECT_DOUBLE_EQ(rec.dt_s, 0.5);
}

TEST(RecordingReader, TimeColumnJitterIsMeasured) {
  std::string text = "t,u,y\n";
  for (int i = 0; i < 101; ++i) {
    const double jitter = (i == 50) ? 0.002 : 0.0;  // one late sample, 2 ms on 10 ms
    text += std::to_string(0.01 * i + jitter) + ",1,2\n";
  }
  const Recording rec = parse_recording(text, "rec.csv");
  EXPECT_TRUE(rec.sampling.has_time);
  EXPECT_NEAR(rec.dt_s, 0.01, 1e-12);
  EXPECT_NEAR(rec.sampling.jitter_max_s, 0.002, 1e-9);
  EXPECT_GT(rec.sampling.jitter_rms_s, 0.0);
  EXPECT_FALSE(rec.sampling.uniform);

  std::string clean = "t,u,y\n";
  for (int i = 0; i < 101; ++i) clean += std::to_string(0.01 * i) + ",1,2\n";
  const Recording ok = parse_recording(clean, "rec.csv");
  EXPECT_TRUE(ok.sampling.uniform);
  EXPECT_LT(ok.sampling.jitter_max_s, 1e-6);
}

TEST(RecordingReader, UnterminatedLastLineIsDroppedWithWarning) {
  const Recording rec = parse_recording("t,u,y\n0,1,2\n0.1,3,4\n0.2,5,6\n0.3,7.1", "rec.csv");
  EXPECT_EQ(rec.rows(), 3);
  ASSERT_EQ(rec.warnings.size(), 1u);
  EXPECT_NE(rec.warnings[0].find("rec.csv:5"), std::string::npos) << rec.warnings[0];
}

TEST(RecordingReader, TabSeparatedWithTrailingTabOnEveryRow) {
  ReadOptions options;
  options.dt_s = 1.0;
  const Recording rec = parse_recording("a\tb\t\n1\t2\t\n3\t4\t\n", "tab.csv", options);
  ASSERT_EQ(rec.names, (std::vector<std::string>{"a", "b"}));
  EXPECT_DOUBLE_EQ(rec.column("b")[1], 4.0);
}

TEST(RecordingReader, OnlyATimeColumnIsAnError) {
  ReadOptions options;
  options.min_rows = 1;
  EXPECT_THROW(parse_recording("t\n0\n1\n", "t.csv", options), InputError);
}

TEST(RecordingReader, CrLfLineEndsAndSemicolonSeparator) {
  const Recording rec = parse_recording("t;u;y\r\n0;1;2\r\n1;3;4\r\n", "rec.csv");
  EXPECT_EQ(rec.rows(), 2);
  EXPECT_DOUBLE_EQ(rec.column("y")[1], 4.0);
}

TEST(RecordingReader, SidecarSuppliesSampleRateAndMetadata) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "rec.csv", "u,y\n1,2\n3,4\n5,6\n");
  write_text(dir / "rec.json",
             R"({"sample_rate_hz": 200, "units": {"u": "%", "y": "kW"}, "coupling_rc_s": 1.6,
                 "operating_point": {"power_kw": 3500}, "preset": "stornoway", "seed": 7,
                 "link": "tcp://127.0.0.1:1502", "extra": [1, 2]})");
  const Recording rec = read_recording(csv);
  EXPECT_DOUBLE_EQ(rec.dt_s, 0.005);
  EXPECT_EQ(rec.sampling.dt_source, "sidecar sample_rate_hz");
  EXPECT_TRUE(rec.sidecar.present);
  EXPECT_EQ(rec.sidecar.units.at("y"), "kW");
  EXPECT_DOUBLE_EQ(*rec.sidecar.coupling_rc_s, 1.6);
  EXPECT_EQ(rec.sidecar.preset, "stornoway");
  EXPECT_EQ(*rec.sidecar.seed, 7u);
  EXPECT_EQ(rec.sidecar.operating_point.at("power_kw"), 3500);
  EXPECT_EQ(rec.sidecar.raw.at("extra").size(), 2u);
}

TEST(RecordingReader, BadSidecarNamesFileAndKey) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "rec.csv", "u,y\n1,2\n3,4\n");
  write_text(dir / "rec.json", R"({"sample_rate_hz": "fast"})");
  try {
    read_recording(csv);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rec.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("sample_rate_hz"), std::string::npos) << e.what();
  }
}

TEST(RecordingReader, OptionDtOverridesTimeColumnWithWarning) {
  ReadOptions options;
  options.dt_s = 0.02;
  const Recording rec = parse_recording("t,u\n0,1\n0.01,2\n0.02,3\n", "rec.csv", options);
  EXPECT_DOUBLE_EQ(rec.dt_s, 0.02);
  EXPECT_EQ(rec.warnings.size(), 1u);
}

TEST(RecordingReader, PublicBenchmarkFilesParse) {
  const char* shared = std::getenv("RIG_SHARED_DIR");
  if (!shared || !std::filesystem::exists(std::filesystem::path(shared) / "data")) {
    GTEST_SKIP() << "RIG_SHARED_DIR not set or has no data/";
  }
  const std::filesystem::path data = std::filesystem::path(shared) / "data";
  const Recording tanks =
      read_recording(data / "nonlinear_benchmarks/cascaded_tanks/dataBenchmark.csv");
  EXPECT_EQ(tanks.rows(), 1024);
  EXPECT_EQ(tanks.names, (std::vector<std::string>{"uEst", "uVal", "yEst", "yVal"}));
  EXPECT_DOUBLE_EQ(tanks.dt_s, 4.0);
  EXPECT_DOUBLE_EQ(tanks.column("yEst").maxCoeff(), 10.0);  // the overflow clip

  ReadOptions options;
  options.dt_s = 0.08;
  const Recording dryer = read_recording(data / "daisy/dryer.dat", options);
  EXPECT_EQ(dryer.rows(), 1000);
  EXPECT_EQ(dryer.names.size(), 2u);
  EXPECT_DOUBLE_EQ(dryer.column("1").maxCoeff(), 6.41);
}

}  // namespace
}  // namespace rig::io
