// Low-level splitting of delimited text into lines and fields, shared by the recording and
// FRF readers. Internal to rig/io.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rig::io::detail {

struct Line {
  std::string_view text;  // without the line end ("\n" or "\r\n")
  long number = 0;        // 1-based line number in the file
};

struct SplitText {
  std::vector<Line> lines;          // non-blank lines; trailing blank lines dropped
  std::optional<long> partial_line; // number of a dropped unterminated last line
  std::optional<long> blank_inside; // first blank line followed by more data
};

SplitText split_lines(std::string_view text);

// ',' ';' or '\t' when the line contains one (in that order), else 0 = runs of whitespace.
char detect_separator(std::string_view first_line);

// Fields of a line; surrounding spaces and double quotes removed. With strip_trailing, one
// trailing separator (MATLAB writes one on every row) is removed first.
std::vector<std::string_view> split_fields(std::string_view line, char separator,
                                           bool strip_trailing);

enum class CellStatus { kOk, kEmpty, kNotNumber, kNotFinite };

// Parses a whole field as a double (a leading '+' allowed); the status says why not.
CellStatus parse_cell(std::string_view field, double& value);

}  // namespace rig::io::detail
