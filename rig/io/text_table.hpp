// Low-level splitting of delimited lines into fields, for the recording reader (which the FRF
// reader uses too). Internal to rig/io.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace rig::io::detail {

// ',' ';' or '\t' when the line contains one (in that order), else 0 = runs of whitespace.
char detect_separator(std::string_view first_line);

// Fields of a line; surrounding spaces and double quotes removed. With strip_trailing, one
// trailing separator (MATLAB writes one on every row) is removed first.
std::vector<std::string_view> split_fields(std::string_view line, char separator,
                                           bool strip_trailing);
// The same into `fields` (cleared first), so a reader can reuse one vector for every line.
void split_fields(std::string_view line, char separator, bool strip_trailing,
                  std::vector<std::string_view>& fields);

enum class CellStatus { kOk, kEmpty, kNotNumber, kNotFinite };

// Parses a whole field as a double (a leading '+' allowed); the status says why not.
CellStatus parse_cell(std::string_view field, double& value);

}  // namespace rig::io::detail
