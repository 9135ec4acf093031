// Writes a recording while a test runs (DESIGN.md sections 2 and 8: "the recording stays
// readable" after a trip or a crash).
//
// Rows are formatted into a memory buffer and handed to the kernel with write(2) in whole
// lines, at least every flush_period, by a background thread. append() only formats under a
// short lock and never waits for a write(2): a realtime tick loop cannot be held up by the disk
// or by the flusher being descheduled (the buffer is swapped out under the lock and written
// outside it). After a kill -9 the file therefore holds every row up to the last flush; if the
// process dies inside write(2) the last line may be cut, and read_recording() drops an
// unterminated last line with a warning. sync_to_disk adds fdatasync(2) per flush so that
// the same holds after a power cut.
//
// The sidecar (rec.json) is written when the file is opened and rewritten on close() with
// "rows" and "complete": true, so a reader can tell a finished recording from a cut one.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "rig/io/sidecar.hpp"

namespace rig::io {

struct RecordingWriterOptions {
  std::chrono::milliseconds flush_period{250};  // must be <= 1 s
  int significant_digits = 10;
  bool sync_to_disk = true;
  bool write_sidecar = true;
};

class RecordingWriter {
 public:
  // Creates (truncates) `csv` and writes the header. InputError when it cannot.
  RecordingWriter(std::filesystem::path csv, std::vector<std::string> columns, Sidecar sidecar = {},
                  RecordingWriterOptions options = {});
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // One row, as many values as columns (std::invalid_argument otherwise). Non-finite
  // values are written as "nan"/"inf" and will be rejected by the reader, on purpose.
  void append(std::span<const double> row);
  void append(std::initializer_list<double> row);
  // Hands buffered rows to the kernel now (and fdatasync when sync_to_disk).
  void flush();
  // Flushes, stops the flusher thread, closes the file, finalises the sidecar. Idempotent.
  void close();

  std::size_t rows() const;
  const std::filesystem::path& path() const { return path_; }

 private:
  void write_out();  // swaps the buffer out and writes it (io_mutex_ serialises writers)
  void cut_back(const std::string& out, std::size_t done);
  void flusher_loop();

  std::filesystem::path path_;
  std::vector<std::string> columns_;
  Sidecar sidecar_;
  RecordingWriterOptions options_;
  int fd_ = -1;
  std::string buffer_;
  std::size_t rows_ = 0;
  off_t committed_bytes_ = 0;      // file length at the last whole row handed to the kernel
  std::size_t lines_written_ = 0;  // whole lines in the file (header included)
  std::string error_;              // first write error, reported by the next append/flush
  mutable std::mutex mutex_;       // buffer_, rows_, error_, stopping_
  std::mutex io_mutex_;            // fd_ writes, committed_bytes_, lines_written_
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread flusher_;
};

}  // namespace rig::io
