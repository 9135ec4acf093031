// The one error type for unreadable input files (recordings, sidecars, models, FRFs), and the
// checked opening of such files.
//
// The message is a single line in compiler style, so a technician can jump to the spot:
//     rec.csv:17: column "y": expected a finite number, found "nan"
// line 0 means "the file as a whole"; column is empty when no column is concerned.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace rig::model {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, long line, std::string column, const std::string& expected);

  const std::string& file() const { return file_; }
  long line() const { return line_; }
  const std::string& column() const { return column_; }

 private:
  std::string file_;
  long line_ = 0;
  std::string column_;
};

// An input file open for reading. Only a regular file (or a symbolic link to one) is
// accepted: a FIFO, a character device such as /dev/zero, a socket or a directory would
// block or never end, so it is refused with
//     /dev/zero: not a regular file (a character device); expected a recording file
// (`what` names the kind of file expected). The file is opened non-blocking, so opening a
// FIFO cannot wait for a writer, and checked with fstat on the open descriptor, so it cannot
// be swapped between the check and the reading.
class InputFile {
 public:
  InputFile(const std::filesystem::path& path, const std::string& what);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  // The size when opened: an estimate (a file being written may have grown since).
  std::uint64_t size() const { return size_; }
  // Up to `n` bytes; 0 at the end of the file. InputError naming the file on a read error.
  std::size_t read(char* data, std::size_t n);

 private:
  std::string name_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

// The whole of a small input file (a sidecar, a model): InputFile's checks, and InputError
// when it holds more than max_bytes.
std::string read_small_input_file(const std::filesystem::path& path, const std::string& what,
                                  std::size_t max_bytes);

}  // namespace rig::model
