#include "rig/io/recording_writer.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "rig/io/input_error.hpp"

namespace rig::io {

RecordingWriter::RecordingWriter(std::filesystem::path csv, std::vector<std::string> columns,
                                 Sidecar sidecar, RecordingWriterOptions options)
    : path_(std::move(csv)),
      columns_(std::move(columns)),
      sidecar_(std::move(sidecar)),
      options_(options) {
  if (columns_.empty()) throw std::invalid_argument("RecordingWriter: no columns");
  if (options_.flush_period > std::chrono::seconds(1) ||
      options_.flush_period <= std::chrono::milliseconds(0)) {
    throw std::invalid_argument("RecordingWriter: flush_period must be in (0, 1 s]");
  }
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw InputError(path_.string(), 0, "", std::string("cannot create: ") + std::strerror(errno));
  }
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    buffer_ += (i ? "," : "") + columns_[i];
  }
  buffer_ += '\n';
  if (options_.write_sidecar) {
    sidecar_.raw["columns"] = columns_;
    sidecar_.raw["complete"] = false;
    write_sidecar(sidecar_path(path_), sidecar_);
  }
  write_out();
  flusher_ = std::thread([this] { flusher_loop(); });
}

RecordingWriter::~RecordingWriter() {
  try {
    close();
  } catch (...) {
    // A destructor must not throw; the error was already reported to append()/flush()
    // callers when it happened.
  }
}

void RecordingWriter::append(std::span<const double> row) {
  if (row.size() != columns_.size()) {
    throw std::invalid_argument(fmt::format("{}: expected {} values per row, got {}",
                                            path_.string(), columns_.size(), row.size()));
  }
  std::lock_guard lock(mutex_);
  if (!error_.empty()) throw InputError(path_.string(), 0, "", error_);
  if (fd_ < 0) throw std::logic_error(path_.string() + ": append after close");
  for (std::size_t i = 0; i < row.size(); ++i) {
    if (i) buffer_ += ',';
    fmt::format_to(std::back_inserter(buffer_), "{:.{}g}", row[i], options_.significant_digits);
  }
  buffer_ += '\n';
  ++rows_;
  if (buffer_.size() > (1u << 16)) wake_.notify_one();  // the flusher writes it
}

void RecordingWriter::append(std::initializer_list<double> row) {
  append(std::span<const double>(row.begin(), row.size()));
}

void RecordingWriter::flush() {
  write_out();
  std::lock_guard lock(mutex_);
  if (!error_.empty()) throw InputError(path_.string(), 0, "", error_);
}

// The buffer always ends at a line end, so each write(2) hands over whole rows. When the
// disk fills in the middle of a row, the file is cut back to the last whole row, so that the
// recording stays readable (DESIGN.md section 8).
void RecordingWriter::write_out() {
  std::lock_guard io(io_mutex_);
  std::string out;
  {
    std::lock_guard lock(mutex_);
    if (fd_ < 0 || buffer_.empty() || !error_.empty()) return;
    out.swap(buffer_);
  }
  std::size_t done = 0;
  while (done < out.size()) {
    const ssize_t n = ::write(fd_, out.data() + done, out.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string error =
          std::string("write failed: ") + std::strerror(n < 0 ? errno : ENOSPC);
      cut_back(out, done);
      std::lock_guard lock(mutex_);
      error_ = error;
      return;
    }
    done += std::size_t(n);
  }
  committed_bytes_ += static_cast<off_t>(done);
  lines_written_ += static_cast<std::size_t>(std::count(out.begin(), out.end(), '\n'));
  if (options_.sync_to_disk) ::fdatasync(fd_);
}

// After a write that stopped `done` bytes into `out`: the file ends at the last whole row.
void RecordingWriter::cut_back(const std::string& out, std::size_t done) {
  const std::size_t whole = done == 0 ? std::string::npos : out.rfind('\n', done - 1);
  const off_t keep =
      committed_bytes_ + (whole == std::string::npos ? 0 : static_cast<off_t>(whole + 1));
  if (::ftruncate(fd_, keep) != 0) return;
  committed_bytes_ = keep;
  if (whole != std::string::npos) {
    lines_written_ += static_cast<std::size_t>(
        std::count(out.begin(), out.begin() + static_cast<long>(whole + 1), '\n'));
  }
}

void RecordingWriter::flusher_loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, options_.flush_period);
    lock.unlock();
    write_out();
    lock.lock();
  }
}

void RecordingWriter::close() {
  {
    std::lock_guard lock(mutex_);
    if (fd_ < 0) return;
    stopping_ = true;
  }
  wake_.notify_all();
  if (flusher_.joinable()) flusher_.join();
  write_out();
  std::lock_guard io(io_mutex_);
  std::lock_guard lock(mutex_);
  ::close(fd_);
  fd_ = -1;
  if (options_.write_sidecar) {
    // The rows the file holds: fewer than appended when the disk filled.
    sidecar_.raw["rows"] = lines_written_ > 0 ? lines_written_ - 1 : 0;
    sidecar_.raw["complete"] = error_.empty();
    write_sidecar(sidecar_path(path_), sidecar_);
  }
  if (!error_.empty()) throw InputError(path_.string(), 0, "", error_);
}

std::size_t RecordingWriter::rows() const {
  std::lock_guard lock(mutex_);
  return rows_;
}

}  // namespace rig::io
