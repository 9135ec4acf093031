#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "rig/io/recording.hpp"
#include "rig/io/recording_writer.hpp"
#include "test_files.hpp"

namespace rig::io {
namespace {

using testing::scratch_dir;

long count_lines(const std::filesystem::path& path) {
  std::ifstream in(path);
  long n = 0;
  std::string line;
  while (std::getline(in, line)) ++n;
  return n;
}

TEST(RecordingWriter, RoundTripWithSidecar) {
  const auto dir = scratch_dir();
  Sidecar meta;
  meta.sample_rate_hz = 100.0;
  meta.units = {{"t", "s"}, {"u", "%"}, {"y", "kW"}};
  meta.preset = "stornoway";
  meta.seed = 11;
  {
    RecordingWriter writer(dir / "rec.csv", {"t", "u", "y"}, meta);
    for (int i = 0; i < 1000; ++i) writer.append({0.01 * i, 0.1 * i, -2.5e-4 * i});
    EXPECT_EQ(writer.rows(), 1000u);
  }
  const Recording rec = read_recording(dir / "rec.csv");
  ASSERT_EQ(rec.rows(), 1000);
  EXPECT_NEAR(rec.dt_s, 0.01, 1e-12);
  EXPECT_TRUE(rec.sampling.uniform);
  EXPECT_DOUBLE_EQ(rec.column("u")[999], 99.9);
  EXPECT_DOUBLE_EQ(rec.column("y")[400], -0.1);
  EXPECT_EQ(rec.sidecar.preset, "stornoway");
  EXPECT_EQ(rec.sidecar.raw.at("rows"), 1000);
  EXPECT_EQ(rec.sidecar.raw.at("complete"), true);
  EXPECT_TRUE(rec.warnings.empty());
}

TEST(RecordingWriter, RejectsRowOfWrongLength) {
  const auto dir = scratch_dir();
  RecordingWriter writer(dir / "rec.csv", {"t", "u"});
  EXPECT_THROW(writer.append({1.0, 2.0, 3.0}), std::invalid_argument);
}

// Rows reach the file within the flush period without any explicit flush() or close().
TEST(RecordingWriter, FlushesPeriodicallyWithoutBeingAsked) {
  const auto dir = scratch_dir();
  RecordingWriterOptions options;
  options.flush_period = std::chrono::milliseconds(100);
  RecordingWriter writer(dir / "rec.csv", {"t", "u"}, {}, options);
  for (int i = 0; i < 10; ++i) writer.append({0.1 * i, double(i)});
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  EXPECT_EQ(count_lines(dir / "rec.csv"), 11);
}

// A writer process killed with SIGKILL leaves a readable recording holding every row up to
// the last flush (the child appends row i = {0.01 i, i} forever).
TEST(RecordingWriter, RecordingIsReadableAfterKillMinus9) {
  const auto dir = scratch_dir();
  const auto csv = dir / "rec.csv";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RecordingWriterOptions options;
    options.flush_period = std::chrono::milliseconds(50);
    options.sync_to_disk = false;
    RecordingWriter writer(csv, {"t", "u"}, {}, options);
    for (long i = 0;; ++i) {
      writer.append({0.01 * double(i), double(i)});
      if (i % 100 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (count_lines(csv) < 2000 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const long seen_before_kill = count_lines(csv) - 1;
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_GE(seen_before_kill, 1999);

  const Recording rec = read_recording(csv);
  EXPECT_GE(rec.rows(), seen_before_kill);
  for (Eigen::Index i = 0; i < rec.rows(); ++i) {
    ASSERT_DOUBLE_EQ(rec.column("u")[i], double(i)) << "row " << i;
  }
  EXPECT_NEAR(rec.dt_s, 0.01, 1e-9);
  EXPECT_EQ(rec.sidecar.raw.at("complete"), false) << "the sidecar shows an unfinished recording";
}

}  // namespace
}  // namespace rig::io
