#include "rig/io/text_table.hpp"

#include <charconv>
#include <cmath>

namespace rig::io::detail {
namespace {

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  s = s.substr(first, last - first + 1);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

}  // namespace

char detect_separator(std::string_view first_line) {
  for (char c : {',', ';', '\t'}) {
    if (first_line.find(c) != std::string_view::npos) {
      // A tab next to spaces (the DaISy files) is plain whitespace.
      if (c == '\t' && first_line.find(' ') != std::string_view::npos) return 0;
      return c;
    }
  }
  return 0;
}

std::vector<std::string_view> split_fields(std::string_view line, char separator,
                                           bool strip_trailing) {
  std::vector<std::string_view> fields;
  split_fields(line, separator, strip_trailing, fields);
  return fields;
}

void split_fields(std::string_view line, char separator, bool strip_trailing,
                  std::vector<std::string_view>& fields) {
  fields.clear();
  if (separator == 0) {
    std::size_t pos = 0;
    while (true) {
      pos = line.find_first_not_of(" \t\r", pos);
      if (pos == std::string_view::npos) break;
      const std::size_t end = line.find_first_of(" \t\r", pos);
      fields.push_back(trim(line.substr(pos, end == std::string_view::npos ? end : end - pos)));
      if (end == std::string_view::npos) break;
      pos = end;
    }
    return;
  }
  std::string_view body = line;
  // Trailing blanks go, but not a trailing tab when the tab is the separator (an empty cell).
  const auto last = body.find_last_not_of(separator == '\t' ? " \r" : " \t\r");
  if (last != std::string_view::npos) body = body.substr(0, last + 1);
  if (strip_trailing && !body.empty() && body.back() == separator) body.remove_suffix(1);
  std::size_t pos = 0;
  while (true) {
    const std::size_t end = body.find(separator, pos);
    fields.push_back(trim(body.substr(pos, end == std::string_view::npos ? end : end - pos)));
    if (end == std::string_view::npos) break;
    pos = end + 1;
  }
}

CellStatus parse_cell(std::string_view field, double& value) {
  if (field.empty()) return CellStatus::kEmpty;
  if (field.front() == '+') field.remove_prefix(1);
  const char* first = field.data();
  const char* last = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ptr != last || (ec != std::errc() && ec != std::errc::result_out_of_range)) {
    return CellStatus::kNotNumber;
  }
  if (ec == std::errc::result_out_of_range || !std::isfinite(value)) {
    return CellStatus::kNotFinite;
  }
  return CellStatus::kOk;
}

}  // namespace rig::io::detail
