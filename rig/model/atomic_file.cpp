#include "rig/model/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "rig/model/input_error.hpp"

namespace rig::model {

void write_file_atomic(const std::filesystem::path& path, std::string_view text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw InputError(path.string(), 0, "", std::string("cannot write: ") + std::strerror(errno));
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = errno;
      ::close(fd);
      throw InputError(path.string(), 0, "", std::string("write failed: ") + std::strerror(err));
    }
    done += static_cast<std::size_t>(n);
  }
  ::fdatasync(fd);
  ::close(fd);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    throw InputError(path.string(), 0, "", "cannot rename the temporary file: " + ec.message());
  }
}

// A model or other small text file: the checks of InputFile (a FIFO or a device such as
// /dev/zero is refused instead of read forever), at most kMaxTextFileBytes.
std::string read_file_text(const std::filesystem::path& path) {
  constexpr std::size_t kMaxTextFileBytes = std::size_t{64} << 20;
  return read_small_input_file(path, "a model", kMaxTextFileBytes);
}

}  // namespace rig::model
