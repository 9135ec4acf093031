#include "rig/model/input_error.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rig::model {
namespace {

std::string compose(const std::string& file, long line, const std::string& column,
                    const std::string& expected) {
  std::string where = line > 0 ? fmt::format("{}:{}", file, line) : file;
  if (!column.empty()) {
    return fmt::format("{}: column \"{}\": {}", where, column, expected);
  }
  return fmt::format("{}: {}", where, expected);
}

const char* file_kind(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISSOCK(mode)) return "a socket";
  return "an unknown kind of file";
}

}  // namespace

InputError::InputError(std::string file, long line, std::string column, const std::string& expected)
    : std::runtime_error(compose(file, line, column, expected)),
      file_(std::move(file)),
      line_(line),
      column_(std::move(column)) {}

InputFile::InputFile(const std::filesystem::path& path, const std::string& what)
    : name_(path.string()) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    throw InputError(name_, 0, "", std::string("cannot open the file: ") + std::strerror(errno));
  }
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    const std::string kind = file_kind(st.st_mode);
    ::close(fd_);
    fd_ = -1;
    throw InputError(name_, 0, "",
                     fmt::format("not a regular file ({}); expected {} file", kind, what));
  }
  // Back to blocking reads (O_NONBLOCK has no effect on a regular file, but say what we mean).
  const int flags = ::fcntl(fd_, F_GETFL);
  if (flags >= 0) ::fcntl(fd_, F_SETFL, flags & ~O_NONBLOCK);
  size_ = st.st_size > 0 ? std::uint64_t(st.st_size) : 0;
}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t InputFile::read(char* data, std::size_t n) {
  while (true) {
    const ssize_t got = ::read(fd_, data, n);
    if (got >= 0) return std::size_t(got);
    if (errno == EINTR) continue;
    throw InputError(name_, 0, "", std::string("read failed: ") + std::strerror(errno));
  }
}

std::string read_small_input_file(const std::filesystem::path& path, const std::string& what,
                                  std::size_t max_bytes) {
  InputFile file(path, what);
  if (file.size() > max_bytes) {
    throw InputError(path.string(), 0, "",
                     fmt::format("expected {} file of at most {} bytes, found {} bytes", what,
                                 max_bytes, file.size()));
  }
  std::string text;
  std::size_t have = 0;
  while (true) {
    // One byte more than allowed, so that a file that grew past the bound is noticed.
    text.resize(std::min(max_bytes + 1, std::max<std::size_t>(have + 65536, file.size() + 1)));
    const std::size_t got = file.read(text.data() + have, text.size() - have);
    if (got == 0) break;
    have += got;
    if (have > max_bytes) {
      throw InputError(
          path.string(), 0, "",
          fmt::format("expected {} file of at most {} bytes, found more", what, max_bytes));
    }
  }
  text.resize(have);
  return text;
}

}  // namespace rig::model
