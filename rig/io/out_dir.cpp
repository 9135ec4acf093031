#include "rig/io/out_dir.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rig::io {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void refuse(const fs::path& dir, const std::string& what) {
  throw OutDirError("--out " + dir.string() + ": " + what);
}

void clear_contents(const fs::path& dir) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    fs::remove_all(entry.path(), ec);
    if (ec) refuse(dir, "--force could not remove " + entry.path().string() + ": " + ec.message());
  }
  if (ec) refuse(dir, "cannot list the folder: " + ec.message());
}

void probe_writable(const fs::path& dir) {
  const fs::path probe = dir / ".rig-write-probe";
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) refuse(dir, std::string("cannot write into the folder: ") + std::strerror(errno));
  const bool wrote = ::write(fd, "x\n", 2) == 2;
  const int err = errno;
  ::close(fd);
  ::unlink(probe.c_str());
  if (!wrote) refuse(dir, std::string("cannot write into the folder: ") + std::strerror(err));
}

}  // namespace

void prepare_out_dir(const fs::path& dir, bool force) {
  if (dir.empty()) throw OutDirError("--out: an output folder is required");
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st)) refuse(dir, "exists and is not a folder");
    const bool empty = fs::is_empty(dir, ec);
    if (ec) refuse(dir, "cannot list the folder: " + ec.message());
    if (!empty) {
      if (!force) {
        refuse(dir,
               "holds files of an earlier run; choose a new folder or add --force to clear "
               "it first");
      }
      clear_contents(dir);
    }
  } else {
    fs::create_directories(dir, ec);
    if (ec) refuse(dir, "cannot create the folder: " + ec.message());
  }
  probe_writable(dir);
}

}  // namespace rig::io
