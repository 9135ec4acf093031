// Table parsing for recordings; the time base is resolved in recording_timebase.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <limits>
#include <set>

#include "rig/io/atomic_file.hpp"
#include "rig/io/recording.hpp"
#include "rig/io/text_table.hpp"

namespace rig::io {

void resolve_time_base(Recording& rec, const ReadOptions& options);  // recording_timebase.cpp

namespace {

using detail::CellStatus;

struct ColumnState {
  std::vector<double> values;
  long first_bad_line = 0;  // first non-empty defect (not a number, NaN/Inf)
  std::string bad_text;
  CellStatus bad_status = CellStatus::kOk;
  long first_empty_line = 0;
  long empty_count = 0;
  bool first_row_empty = false;
};

bool is_time_name(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lower == "t" || lower == "t_s" || lower == "time" || lower == "time_s";
}

std::vector<std::string> header_names(const std::vector<std::string_view>& fields,
                                      bool is_header, const std::string& source, long line) {
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    std::string name = is_header ? std::string(fields[i]) : index_column_name(int(i) + 1);
    if (name.empty()) name = index_column_name(int(i) + 1);
    if (!seen.insert(name).second) {
      throw InputError(source, line, name, "expected unique column names, found a duplicate");
    }
    names.push_back(name);
  }
  return names;
}

bool looks_like_header(const std::vector<std::string_view>& fields) {
  for (std::string_view f : fields) {
    double v = 0;
    if (detail::parse_cell(f, v) == CellStatus::kNotNumber) return true;
  }
  return false;
}

void parse_rows(const detail::SplitText& split, std::size_t first, char sep, bool strip,
                const std::vector<std::string>& names, const std::string& source,
                std::vector<ColumnState>& cols) {
  for (std::size_t li = first; li < split.lines.size(); ++li) {
    const detail::Line& line = split.lines[li];
    const auto fields = detail::split_fields(line.text, sep, strip);
    if (fields.size() != names.size()) {
      throw InputError(source, line.number, "",
                       fmt::format("expected {} fields, found {}", names.size(), fields.size()));
    }
    const bool first_row = li == first;
    for (std::size_t c = 0; c < fields.size(); ++c) {
      ColumnState& col = cols[c];
      double v = std::numeric_limits<double>::quiet_NaN();
      const CellStatus status = detail::parse_cell(fields[c], v);
      if (status == CellStatus::kEmpty) {
        if (first_row) col.first_row_empty = true;
        if (col.first_empty_line == 0) col.first_empty_line = line.number;
        ++col.empty_count;
      } else if (status != CellStatus::kOk && col.first_bad_line == 0) {
        col.first_bad_line = line.number;
        col.bad_text = std::string(fields[c]);
        col.bad_status = status;
      }
      col.values.push_back(v);
    }
  }
}

// Where a requested column lives: its name, or a 1-based index for any file.
std::size_t find_requested(const std::vector<std::string>& names, const std::string& wanted,
                           const std::string& source) {
  const auto it = std::find(names.begin(), names.end(), wanted);
  if (it != names.end()) return std::size_t(it - names.begin());
  int index = 0;
  const auto [ptr, ec] = std::from_chars(wanted.data(), wanted.data() + wanted.size(), index);
  if (ec == std::errc() && ptr == wanted.data() + wanted.size() && index >= 1 &&
      std::size_t(index) <= names.size()) {
    return std::size_t(index - 1);
  }
  std::string present;
  for (const auto& n : names) present += (present.empty() ? "" : ", ") + n;
  throw InputError(source, 0, wanted, "missing column (the file has: " + present + ")");
}

void check_column(const ColumnState& col, const std::string& name, const std::string& source) {
  if (col.first_bad_line != 0 && (col.first_empty_line == 0 || col.first_bad_line < col.first_empty_line)) {
    const char* what = col.bad_status == CellStatus::kNotFinite
                           ? "expected a finite number, found NaN/Inf or out of range"
                           : "expected a number, found";
    throw InputError(source, col.first_bad_line, name,
                     fmt::format("{} \"{}\"", what, col.bad_text));
  }
  if (col.first_empty_line != 0) {
    throw InputError(source, col.first_empty_line, name, "expected a number, found an empty cell");
  }
}

// A first-row-only column (MATLAB writes Ts and fs that way).
bool is_scalar(const ColumnState& col) {
  return col.values.size() >= 2 && !col.first_row_empty && col.first_bad_line == 0 &&
         col.empty_count == long(col.values.size()) - 1;
}

Eigen::VectorXd to_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), Eigen::Index(v.size()));
}

void keep_columns(std::vector<ColumnState>& cols, const std::vector<std::string>& names,
                  const ReadOptions& options, const std::string& source, Recording& rec) {
  std::vector<std::size_t> keep;
  for (const auto& wanted : options.columns) keep.push_back(find_requested(names, wanted, source));
  const bool all = options.columns.empty();
  for (std::size_t c = 0; c < names.size(); ++c) {
    const bool requested = std::find(keep.begin(), keep.end(), c) != keep.end();
    if (is_scalar(cols[c]) && !requested) {
      rec.scalars[names[c]] = cols[c].values.front();
      continue;
    }
    const bool is_time = !rec.time_s && rec.has_header && is_time_name(names[c]) && !requested;
    if (!all && !requested && !is_time) continue;
    check_column(cols[c], names[c], source);
    if (is_time) {
      rec.time_s = to_vector(cols[c].values);
      rec.time_name = names[c];
    }
  }
  if (all) {
    for (std::size_t c = 0; c < names.size(); ++c) {
      if (!rec.scalars.count(names[c]) && names[c] != rec.time_name) keep.push_back(c);
    }
  }
  for (std::size_t c : keep) {
    rec.names.push_back(names[c]);
    rec.columns.push_back(to_vector(cols[c].values));
  }
}

}  // namespace

std::string index_column_name(int index_1based) { return std::to_string(index_1based); }

bool Recording::has(const std::string& name) const {
  return std::find(names.begin(), names.end(), name) != names.end();
}

const Eigen::VectorXd& Recording::column(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    std::string present;
    for (const auto& n : names) present += (present.empty() ? "" : ", ") + n;
    throw InputError(source, 0, name, "missing column (available: " + present + ")");
  }
  return columns[std::size_t(it - names.begin())];
}

Recording parse_table(std::string_view text, const std::string& source,
                      const ReadOptions& options) {
  const detail::SplitText split = detail::split_lines(text);
  Recording rec;
  rec.source = source;
  if (split.partial_line) {
    rec.warnings.push_back(fmt::format(
        "{}:{}: the last line has no line end (a partially written row): ignored", source,
        *split.partial_line));
  }
  if (split.lines.empty()) throw InputError(source, 0, "", "expected data rows, the file is empty");
  if (split.blank_inside) {
    throw InputError(source, *split.blank_inside, "", "expected a data row, found a blank line");
  }
  const detail::Line& first = split.lines.front();
  const char sep = detail::detect_separator(first.text);
  // MATLAB ends every row with a separator when the header line ends with one.
  const auto last = first.text.find_last_not_of(sep == '\t' ? " \r" : " \t\r");
  const bool strip = sep != 0 && last != std::string_view::npos && first.text[last] == sep;
  const auto first_fields = detail::split_fields(first.text, sep, strip);
  rec.has_header = looks_like_header(first_fields);
  const auto names = header_names(first_fields, rec.has_header, source, first.number);
  std::vector<ColumnState> cols(names.size());
  if (split.lines.size() > (rec.has_header ? 1u : 0u)) {
    rec.first_data_line = split.lines[rec.has_header ? 1 : 0].number;
  }
  parse_rows(split, rec.has_header ? 1 : 0, sep, strip, names, source, cols);
  const std::size_t rows = cols.empty() ? 0 : cols.front().values.size();
  if (Eigen::Index(rows) < options.min_rows) {
    throw InputError(source, 0, "", fmt::format("expected at least {} data rows, found {}",
                                                options.min_rows, rows));
  }
  keep_columns(cols, names, options, source, rec);
  if (rec.names.empty()) {
    throw InputError(source, 0, "", "expected at least one data column besides the time column");
  }
  return rec;
}

Recording parse_recording(std::string_view text, const std::string& source,
                          const ReadOptions& options) {
  Recording rec = parse_table(text, source, options);
  resolve_time_base(rec, options);
  return rec;
}

Recording read_recording(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string text = read_file_text(path);
  Recording rec = parse_table(text, path.string(), options);
  const std::filesystem::path side = sidecar_path(path);
  if (options.read_sidecar && side != path && std::filesystem::exists(side)) {
    rec.sidecar = read_sidecar(side);
  }
  resolve_time_base(rec, options);
  return rec;
}

}  // namespace rig::io
