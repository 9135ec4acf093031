#include "rig/io/input_error.hpp"

#include <fmt/format.h>

namespace rig::io {
namespace {

std::string compose(const std::string& file, long line, const std::string& column,
                    const std::string& expected) {
  std::string where = line > 0 ? fmt::format("{}:{}", file, line) : file;
  if (!column.empty()) {
    return fmt::format("{}: column \"{}\": {}", where, column, expected);
  }
  return fmt::format("{}: {}", where, expected);
}

}  // namespace

InputError::InputError(std::string file, long line, std::string column,
                       const std::string& expected)
    : std::runtime_error(compose(file, line, column, expected)),
      file_(std::move(file)),
      line_(line),
      column_(std::move(column)) {}

}  // namespace rig::io
