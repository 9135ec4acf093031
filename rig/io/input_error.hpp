// The one error type for unreadable input files (recordings, sidecars, models, FRFs).
//
// The message is a single line in compiler style, so a technician can jump to the spot:
//     rec.csv:17: column "y": expected a finite number, found "nan"
// line 0 means "the file as a whole"; column is empty when no column is concerned.
#pragma once

#include <stdexcept>
#include <string>

namespace rig::io {

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

}  // namespace rig::io
