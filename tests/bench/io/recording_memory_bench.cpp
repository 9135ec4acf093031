// Peak memory of rig::io::read_recording on a large generated recording.
//
//   bench_recording_memory [--mb 200] [--cols 11] [--file /tmp/rig_bench_recording.csv] [--keep]
//                          [--read EXISTING.csv] [--columns u,y]
//
// Writes a CSV of about --mb megabytes (a time column "t" plus cols-1 columns, every cell
// about 15 characters, e.g. "-1.234567890e+00"), or takes --read FILE as it is (not
// removed), then reads it in a forked child (only --columns, when given) and prints
// the child's peak resident memory (getrusage ru_maxrss) above its resident size before the
// read, against the size of the parsed data (rows x columns x 8 bytes), and the ratio. The
// aim is a ratio of about 1.3 or less: the reader streams the text and keeps only the doubles.
// The file is removed afterwards unless --keep.
#include <fmt/format.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "rig/io/recording.hpp"

namespace {

long rss_kib() {  // current resident size, from /proc/self/statm
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  long pages = 0, resident = 0;
  if (f) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return resident * (::sysconf(_SC_PAGESIZE) / 1024);
}

long max_rss_kib() {
  rusage ru{};
  ::getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss;
}

// Writes the CSV in 1 MiB pieces, so the generator itself stays small. Returns the rows.
long generate(const std::string& path, double megabytes, int cols) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    std::perror(path.c_str());
    std::exit(2);
  }
  std::string buf = "t";
  for (int c = 1; c < cols; ++c) buf += c == 1 ? ",u" : c == 2 ? ",y" : fmt::format(",c{}", c);
  buf += '\n';
  const double target = megabytes * 1e6;
  double written = 0;
  long rows = 0;
  while (written + double(buf.size()) < target) {
    fmt::format_to(std::back_inserter(buf), "{:.9e}", 0.001 * double(rows));
    for (int c = 1; c < cols; ++c) {
      fmt::format_to(std::back_inserter(buf), ",{:.9e}", std::sin(0.01 * double(rows) + c) * 3.7);
    }
    buf += '\n';
    ++rows;
    if (buf.size() > (1u << 20)) {
      written += double(std::fwrite(buf.data(), 1, buf.size(), f));
      buf.clear();
    }
  }
  std::fwrite(buf.data(), 1, buf.size(), f);
  std::fclose(f);
  return rows;
}

struct Figures {
  long rss_before_kib, max_rss_before_kib, max_rss_after_kib, rows, cols;
  double seconds;
};

}  // namespace

int main(int argc, char** argv) {
  double mb = 200;
  int cols = 11;
  std::string file = "/tmp/rig_bench_recording.csv";
  bool keep = false;
  std::string existing;
  rig::io::ReadOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--mb" && i + 1 < argc)
      mb = std::atof(argv[++i]);
    else if (a == "--cols" && i + 1 < argc)
      cols = std::atoi(argv[++i]);
    else if (a == "--file" && i + 1 < argc)
      file = argv[++i];
    else if (a == "--keep")
      keep = true;
    else if (a == "--read" && i + 1 < argc)
      existing = argv[++i];
    else if (a == "--columns" && i + 1 < argc) {
      std::string list = argv[++i];
      for (std::size_t pos = 0; pos <= list.size();) {
        const std::size_t comma = std::min(list.find(',', pos), list.size());
        options.columns.push_back(list.substr(pos, comma - pos));
        pos = comma + 1;
      }
    } else {
      std::fprintf(stderr,
                   "usage: %s [--mb N] [--cols C] [--file PATH] [--keep] [--read FILE] "
                   "[--columns A,B]\n",
                   argv[0]);
      return 2;
    }
  }
  if (cols < 2 || !(mb > 0)) {
    std::fprintf(stderr, "expected --cols >= 2 and --mb > 0\n");
    return 2;
  }
  if (existing.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    const long rows = generate(file, mb, cols);
    const double gen_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    fmt::print("file      {} ({:.1f} MB, {} rows x {} columns, written in {:.1f} s)\n", file,
               double(std::filesystem::file_size(file)) / 1e6, rows, cols, gen_s);
  } else {
    file = existing;
    keep = true;
    fmt::print("file      {} ({:.1f} MB)\n", file, double(std::filesystem::file_size(file)) / 1e6);
  }
  const auto bytes = std::filesystem::file_size(file);

  int fds[2];
  if (::pipe(fds) != 0) return 2;
  const pid_t pid = ::fork();
  if (pid == 0) {  // the child reads
    ::close(fds[0]);
    ::malloc_trim(0);  // free heap pages the parent left would hide part of the growth
    Figures f{};
    f.rss_before_kib = rss_kib();
    f.max_rss_before_kib = max_rss_kib();
    const auto start = std::chrono::steady_clock::now();
    try {
      const rig::io::Recording rec = rig::io::read_recording(file, options);
      f.rows = rec.rows();
      f.cols = long(rec.columns.size()) + (rec.time_s ? 1 : 0);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "read failed: %s\n", e.what());
      ::_exit(1);
    }
    f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    f.max_rss_after_kib = max_rss_kib();
    if (::write(fds[1], &f, sizeof f) != ssize_t(sizeof f)) ::_exit(1);
    ::_exit(0);
  }
  ::close(fds[1]);
  Figures f{};
  const bool got = ::read(fds[0], &f, sizeof f) == ssize_t(sizeof f);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (!keep) std::filesystem::remove(file);
  if (!got || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "the reading child failed\n");
    return 1;
  }
  const double parsed_mb = double(f.rows) * double(f.cols) * 8.0 / 1e6;
  // The child's ru_maxrss starts at the parent's size at the fork; the growth is counted from
  // the child's resident size after malloc_trim, which may only overstate it.
  const long base = f.rss_before_kib;
  const double growth_mb = double(f.max_rss_after_kib - base) * 1024.0 / 1e6;
  fmt::print("read      {} rows x {} columns in {:.2f} s ({:.0f} MB/s)\n", f.rows, f.cols,
             f.seconds, double(bytes) / 1e6 / f.seconds);
  fmt::print("parsed    {:.1f} MB of doubles\n", parsed_mb);
  fmt::print(
      "peak RSS  {:.1f} MB above the {:.1f} MB resident before the read (ru_maxrss {} KiB "
      "before, {} KiB after)\n",
      growth_mb, double(base) * 1024.0 / 1e6, f.max_rss_before_kib, f.max_rss_after_kib);
  fmt::print("ratio     {:.3f} (peak RSS growth / parsed data; aim <= 1.3)\n",
             growth_mb / parsed_mb);
  fmt::print("text      {:.3f} (peak RSS growth / file size)\n", growth_mb / (double(bytes) / 1e6));
  return 0;
}
