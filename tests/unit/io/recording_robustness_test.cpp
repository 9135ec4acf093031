// Files that used to be read wrongly or not at all: a sidecar rate that contradicts the time
// column, a UTF-8 byte-order mark, a FIFO or device instead of a file, a file without line
// ends, and the memory a large recording takes (streamed reading).
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "rig/io/recording.hpp"
#include "test_files.hpp"

namespace rig::io {
namespace {

using testing::scratch_dir;
using testing::write_text;

// The InputError of reading `path`, or a test failure.
InputError read_error(const std::filesystem::path& path, const ReadOptions& options = {}) {
  try {
    read_recording(path, options);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line: " << e.what();
    return e;
  }
  ADD_FAILURE() << "expected InputError reading " << path;
  return InputError(path.string(), 0, "", "no error");
}

void expect_contains(const std::string& message, const std::string& piece) {
  EXPECT_NE(message.find(piece), std::string::npos) << "\"" << piece << "\" not in: " << message;
}

// t at 100 Hz (0.01 s steps), n rows.
std::string csv_100hz(int n) {
  std::string text = "t,u,y\n";
  for (int i = 0; i < n; ++i) text += fmt::format("{:.2f},{},{}\n", 0.01 * i, i % 3, i % 5);
  return text;
}

// --- 1. the sidecar's sample_rate_hz against the time column ---------------------------

TEST(SidecarRate, ContradictingTheTimeColumnIsRefusedNamingBothFigures) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "rec.csv", csv_100hz(50));
  write_text(dir / "rec.json", R"({"sample_rate_hz": 50})");
  const InputError e = read_error(csv);
  const std::string m = e.what();
  EXPECT_EQ(e.file(), (dir / "rec.json").string());
  EXPECT_EQ(m.rfind((dir / "rec.json").string() + ": key \"sample_rate_hz\": ", 0), 0u) << m;
  expect_contains(m, "expected 100 Hz as the time column \"t\" of " + csv.string());
  expect_contains(m, "mean step 0.01 s");
  expect_contains(m, "found 50 Hz");
  expect_contains(m, "within 1 %");
  expect_contains(m, "--dt");
}

TEST(SidecarRate, AgreementWithinOnePercentIsAccepted) {
  for (const double rate : {100.0, 100.9, 99.1}) {
    const auto dir = scratch_dir();
    const auto csv = write_text(dir / "rec.csv", csv_100hz(50));
    write_text(dir / "rec.json", fmt::format(R"({{"sample_rate_hz": {}}})", rate));
    const Recording rec = read_recording(csv);
    EXPECT_NEAR(rec.dt_s, 0.01, 1e-12) << rate;  // the time column stays the time base
    EXPECT_TRUE(rec.warnings.empty()) << rate;
  }
  for (const double rate : {101.5, 98.5, 60.0, 1000.0}) {
    const auto dir = scratch_dir();
    const auto csv = write_text(dir / "rec.csv", csv_100hz(50));
    write_text(dir / "rec.json", fmt::format(R"({{"sample_rate_hz": {}}})", rate));
    expect_contains(read_error(csv).what(), fmt::format("found {:g} Hz", rate));
  }
}

TEST(SidecarRate, OptionDtOverridesTheContradictionWithAWarning) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "rec.csv", csv_100hz(50));
  write_text(dir / "rec.json", R"({"sample_rate_hz": 50})");
  ReadOptions options;
  options.dt_s = 0.01;
  const Recording rec = read_recording(csv, options);
  EXPECT_DOUBLE_EQ(rec.dt_s, 0.01);
  ASSERT_FALSE(rec.warnings.empty());
  expect_contains(rec.warnings[0], "sample_rate_hz");
  expect_contains(rec.warnings[0], "--dt 0.01 s overrides both");
}

TEST(SidecarRate, ContradictingAScalarTsColumnIsRefused) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "rec.csv", "u,y,Ts\n1,2,0.1\n3,4,\n5,6,\n");
  write_text(dir / "rec.json", R"({"sample_rate_hz": 100})");
  const InputError e = read_error(csv);
  EXPECT_EQ(e.file(), (dir / "rec.json").string());
  expect_contains(e.what(), "expected 10 Hz as the scalar column Ts of " + csv.string());
  expect_contains(e.what(), "found 100 Hz");
}

TEST(SidecarRate, WithoutATimeColumnTheSidecarIsTheTimeBase) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "rec.csv", "u,y\n1,2\n3,4\n");
  write_text(dir / "rec.json", R"({"sample_rate_hz": 250})");
  EXPECT_DOUBLE_EQ(read_recording(csv).dt_s, 0.004);
}

// --- 2. byte-order marks ---------------------------------------------------------------

TEST(ByteOrderMark, Utf8MarkIsSkippedSoTheTimeColumnIsFound) {
  const std::string text = "\xEF\xBB\xBF" + csv_100hz(5);
  const Recording mem = parse_recording(text, "bom.csv");
  EXPECT_EQ(mem.time_name, "t");
  EXPECT_EQ(mem.names, (std::vector<std::string>{"u", "y"}));
  EXPECT_NEAR(mem.dt_s, 0.01, 1e-12);

  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "bom.csv",
                              "\xEF\xBB\xBF"
                              "t;u;y\r\n0;1;2\r\n0.5;3;4\r\n");
  write_text(dir / "bom.json", "\xEF\xBB\xBF{\"sample_rate_hz\": 2}");  // a BOM there too
  const Recording rec = read_recording(csv);
  EXPECT_EQ(rec.time_name, "t");
  EXPECT_DOUBLE_EQ(rec.dt_s, 0.5);
  EXPECT_DOUBLE_EQ(rec.column("y")[1], 4.0);
  EXPECT_EQ(*rec.sidecar.sample_rate_hz, 2.0);
}

TEST(ByteOrderMark, HeaderlessFileWithAMarkStillHasNumbersFirst) {
  ReadOptions options;
  options.dt_s = 1.0;
  const Recording rec = parse_recording(
      "\xEF\xBB\xBF"
      "1 2\n3 4\n",
      "bom.dat", options);
  EXPECT_FALSE(rec.has_header);
  EXPECT_DOUBLE_EQ(rec.column("1")[0], 1.0);
}

TEST(ByteOrderMark, Utf16IsRefusedOnLineOne) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "wide.csv", std::string("\xFF\xFEt\0,\0u\0\n\0", 12));
  const InputError e = read_error(csv);
  EXPECT_EQ(e.line(), 1);
  expect_contains(e.what(), csv.string() + ":1: expected UTF-8 or ASCII text, found UTF-16");
}

// --- 3. not a regular file; lines without end ------------------------------------------

TEST(NotARegularFile, FifoIsRefusedWithoutWaitingForAWriter) {
  const auto dir = scratch_dir();
  const auto fifo = dir / "rec.csv";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const InputError e = read_error(fifo);
  EXPECT_EQ(e.file(), fifo.string());
  EXPECT_EQ(std::string(e.what()),
            fifo.string() + ": not a regular file (a FIFO); expected a recording file");
}

TEST(NotARegularFile, CharacterDeviceAndDirectoryAreRefused) {
  expect_contains(read_error("/dev/zero").what(),
                  "/dev/zero: not a regular file (a character device)");
  const auto dir = scratch_dir();
  expect_contains(read_error(dir).what(), "not a regular file (a directory)");
  expect_contains(read_error(dir / "missing.csv").what(),
                  (dir / "missing.csv").string() + ": cannot open the file: No such file");
}

TEST(NotARegularFile, SidecarFifoIsRefusedNamingTheSidecar) {
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "rec.csv", csv_100hz(5));
  ASSERT_EQ(::mkfifo((dir / "rec.json").c_str(), 0600), 0);
  const InputError e = read_error(csv);
  EXPECT_EQ(e.file(), (dir / "rec.json").string());
  expect_contains(e.what(), "not a regular file (a FIFO); expected a sidecar file");
}

TEST(LineLength, FileWithoutLineEndsIsRefusedNamingTheLine) {
  const auto dir = scratch_dir();
  const auto blob = write_text(dir / "blob.csv", std::string(3u << 20, '\0'));
  const InputError e = read_error(blob);
  EXPECT_EQ(e.line(), 1);
  expect_contains(e.what(), blob.string() + ":1: expected lines of at most 64 KiB (65536 bytes)");

  const auto late = write_text(dir / "late.csv", "t,u\n0,1\n" + std::string(200000, '7') + "\n");
  EXPECT_EQ(read_error(late).line(), 3);
  EXPECT_THROW(parse_recording("t,u\n0,1\n" + std::string(kMaxLineBytes + 1, '7'), "m.csv"),
               InputError);
}

TEST(LineLength, TheLimitItselfIsAccepted) {
  // A data line padded with blanks to exactly kMaxLineBytes (before its "\r\n") is fine.
  std::string line = "0.5,3";
  line.insert(4, std::string(kMaxLineBytes - line.size() - 1, ' '));
  line += "\r";
  ASSERT_EQ(line.size(), kMaxLineBytes);
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "wide.csv", "t,u\n0,1\n" + line + "\n");
  const Recording rec = read_recording(csv);
  EXPECT_DOUBLE_EQ(rec.column("u")[1], 3.0);
  const auto over = write_text(dir / "over.csv", "t,u\n0,1\n " + line + "\n");
  EXPECT_EQ(read_error(over).line(), 3);
}

// --- 4. streamed reading ---------------------------------------------------------------

// Lines cut by the 1 MiB chunks: reading the file gives what parsing the text gives.
TEST(StreamedReading, ChunkBoundariesChangeNothing) {
  std::string text = "\xEF\xBB\xBF\"t\",\"u\",\"y\",\"Ts\",\r\n";
  for (int i = 0; i < 90000; ++i) {
    text += fmt::format("{:.3f},{:.9g},{},{},\r\n", 0.001 * i, std::sin(0.37 * i), i % 11,
                        i == 0 ? "0.001" : "");
  }
  text += "\n\n";
  ASSERT_GT(text.size(), 2u << 20);
  const auto dir = scratch_dir();
  const auto csv = write_text(dir / "big.csv", text);
  const Recording a = read_recording(csv);
  const Recording b = parse_recording(text, csv.string());
  ASSERT_EQ(a.rows(), 90000);
  EXPECT_EQ(a.names, b.names);
  EXPECT_EQ(a.names, (std::vector<std::string>{"u", "y"}));
  EXPECT_EQ(a.scalars, b.scalars);
  ASSERT_TRUE(a.time_s && b.time_s);
  EXPECT_EQ(*a.time_s, *b.time_s);
  for (std::size_t c = 0; c < a.columns.size(); ++c) EXPECT_EQ(a.columns[c], b.columns[c]);
  EXPECT_NEAR(a.column("u")[89999], std::sin(0.37 * 89999), 1e-8);
  EXPECT_DOUBLE_EQ(a.dt_s, b.dt_s);

  // A defect far into the file is still reported with its line.
  const auto bad = write_text(dir / "bad.csv", text.substr(0, text.size() - 2) + "90,1\n");
  EXPECT_EQ(read_error(bad).line(), 90002);
}

// Resident size now (ru_maxrss is the peak so far; in a forked child, the parent's size).
long resident_kib() {
  long pages = 0, resident = 0;
  std::ifstream("/proc/self/statm") >> pages >> resident;
  return resident * (::sysconf(_SC_PAGESIZE) / 1024);
}

// Peak resident memory of reading a ~20 MB CSV (11 columns of ~15 characters) in a forked
// child, against the parsed doubles: the old reader held the text and vectors (about 4.6x);
// the streamed one about 1.0x. The bound leaves room for allocator rounding and the 1 MiB
// read buffer. (build/bin/bench_recording_memory measures the same on 200 MB.)
TEST(StreamedReading, PeakMemoryIsAboutTheParsedData) {
  const auto dir = scratch_dir();
  const auto path = dir / "large.csv";
  long rows = 0;
  {
    std::ofstream out(path, std::ios::binary);
    std::string buf = "t,u,y,c3,c4,c5,c6,c7,c8,c9,c10\n";
    for (; rows < 115000; ++rows) {
      fmt::format_to(std::back_inserter(buf), "{:.9e}", 0.001 * double(rows));
      for (int c = 1; c < 11; ++c) {
        fmt::format_to(std::back_inserter(buf), ",{:.9e}", std::cos(0.01 * double(rows) + c));
      }
      buf += '\n';
      if (buf.size() > (1u << 20)) out << buf, buf.clear();
    }
    out << buf;
  }
  ASSERT_GT(std::filesystem::file_size(path), 19'000'000u);
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(fds[0]);
    ::malloc_trim(0);  // free heap pages the parent left would hide part of the growth
    long result[3] = {resident_kib(), 0, 0};
    rusage after{};
    try {
      const Recording rec = read_recording(path);
      result[2] = long(rec.rows()) * long(rec.columns.size() + 1);
    } catch (...) {
      ::_exit(1);
    }
    ::getrusage(RUSAGE_SELF, &after);
    result[1] = after.ru_maxrss;
    const bool ok = ::write(fds[1], result, sizeof result) == ssize_t(sizeof result);
    ::_exit(ok ? 0 : 1);
  }
  ::close(fds[1]);
  long result[3] = {0, 0, 0};
  const bool got = ::read(fds[0], result, sizeof result) == ssize_t(sizeof result);
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(got && WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_EQ(result[2], rows * 11);
  const double parsed_mb = double(result[2]) * 8.0 / 1e6;
  const double growth_mb = double(result[1] - result[0]) * 1024.0 / 1e6;
  std::printf("peak RSS growth %.1f MB for %.1f MB of parsed doubles (ratio %.3f)\n", growth_mb,
              parsed_mb, growth_mb / parsed_mb);
  EXPECT_LT(growth_mb, 1.3 * parsed_mb + 3.0);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace rig::io
