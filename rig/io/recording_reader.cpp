// Table parsing for recordings, streamed: the text is cut into lines a chunk at a time
// (LineSplitter) and every line parsed at once into the columns that can be kept
// (TableBuilder), so only the doubles are held. The time base is resolved in
// recording_timebase.cpp.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>

#include "rig/io/recording.hpp"
#include "rig/io/text_table.hpp"

namespace rig::io {

void resolve_time_base(Recording& rec, const ReadOptions& options);  // recording_timebase.cpp

namespace {

using detail::CellStatus;

constexpr std::size_t kChunkBytes = std::size_t(1) << 20;

struct ColumnState {
  // Values are held only for a column that may end up in the Recording (requested, a time
  // column candidate, or every column when none is requested), and only while it has no
  // defect: a column with an empty or bad cell is either refused or not kept.
  bool store = false;
  Eigen::VectorXd values;  // storage for TableBuilder's capacity; the first rows are filled
  long taken_at = -1;      // index in Recording::columns once moved there
  double first_value = std::numeric_limits<double>::quiet_NaN();
  long first_bad_line = 0;  // first non-empty defect (not a number, NaN/Inf)
  std::string bad_text;
  CellStatus bad_status = CellStatus::kOk;
  long first_empty_line = 0;
  long empty_count = 0;
  bool first_row_empty = false;

  void stop_storing() {
    store = false;
    values = Eigen::VectorXd();  // frees the storage
  }
};

bool is_time_name(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lower == "t" || lower == "t_s" || lower == "time" || lower == "time_s";
}

bool is_blank(std::string_view s) {
  return s.find_first_not_of(" \t\r\f\v") == std::string_view::npos;
}

std::vector<std::string> header_names(const std::vector<std::string_view>& fields, bool is_header,
                                      const std::string& source, long line) {
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
  if (col.first_bad_line != 0 &&
      (col.first_empty_line == 0 || col.first_bad_line < col.first_empty_line)) {
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

// Physical memory, to keep a size estimate (a sparse or lying file) from asking for more.
std::uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return std::uint64_t(1) << 34;
  return std::uint64_t(pages) * std::uint64_t(page);
}

// Parses lines as they come into columns of doubles.
class TableBuilder {
 public:
  TableBuilder(std::string source, const ReadOptions& options, std::uint64_t size_hint)
      : source_(std::move(source)), options_(options), size_hint_(size_hint) {}

  bool started() const { return started_; }

  // A terminated, non-blank line; `begin`/`end` are its byte offsets in the file (end past
  // its line end), for the estimate of the number of rows.
  void add_line(std::string_view text, long number, std::uint64_t begin, std::uint64_t end) {
    if (!started_) {
      start(text, number);
      if (has_header_) {
        data_begin_ = end;
        return;
      }
      data_begin_ = begin;
    }
    add_row(text, number, end);
  }

  Recording finish(std::optional<long> partial_line) {
    Recording rec;
    rec.source = source_;
    if (partial_line) {
      rec.warnings.push_back(
          fmt::format("{}:{}: the last line has no line end (a partially written row): ignored",
                      source_, *partial_line));
    }
    if (!started_) throw InputError(source_, 0, "", "expected data rows, the file is empty");
    rec.has_header = has_header_;
    rec.first_data_line = first_data_line_;
    if (rows_ < options_.min_rows) {
      throw InputError(
          source_, 0, "",
          fmt::format("expected at least {} data rows, found {}", options_.min_rows, rows_));
    }
    keep_columns(rec);
    if (rec.names.empty()) {
      throw InputError(source_, 0, "", "expected at least one data column besides the time column");
    }
    return rec;
  }

 private:
  void start(std::string_view first, long number) {
    started_ = true;
    sep_ = detail::detect_separator(first);
    // MATLAB ends every row with a separator when the header line ends with one.
    const auto last = first.find_last_not_of(sep_ == '\t' ? " \r" : " \t\r");
    strip_ = sep_ != 0 && last != std::string_view::npos && first[last] == sep_;
    detail::split_fields(first, sep_, strip_, fields_);
    has_header_ = looks_like_header(fields_);
    names_ = header_names(fields_, has_header_, source_, number);
    cols_.resize(names_.size());
    // Resolved now, so that a wrong name fails before a large file is read.
    for (const auto& wanted : options_.columns) {
      requested_.push_back(find_requested(names_, wanted, source_));
    }
    for (std::size_t c = 0; c < names_.size(); ++c) {
      const bool requested = std::find(requested_.begin(), requested_.end(), c) != requested_.end();
      cols_[c].store =
          options_.columns.empty() || requested || (has_header_ && is_time_name(names_[c]));
    }
  }

  // Room for more rows: the rows still to come are estimated from the bytes left in the file
  // and the mean length of a row so far, so that the storage is reserved about once (storage
  // reserved but never written costs address space, not memory). Never less than 1/8 more,
  // so that a poor estimate still costs a bounded number of moves.
  void grow(std::uint64_t end) {
    const double per_row = double(end - data_begin_) / double(rows_ + 1);
    const double left = size_hint_ > end ? double(size_hint_ - end) : 0.0;
    const double margin = rows_ < 64 ? 1.25 : 1.05;  // a few first rows say little
    double want = double(rows_ + 1) + margin * left / std::max(per_row, 1.0) + 16.0;
    want = std::max(want, double(capacity_) * 1.125 + 16.0);
    std::size_t stored = 0;
    for (const auto& col : cols_) stored += col.store ? 1 : 0;
    if (stored > 0) {
      const double limit = double(physical_memory_bytes()) / 2.0 / (8.0 * double(stored));
      want = std::min(want, std::max(limit, double(capacity_) * 1.125 + 16.0));
    }
    capacity_ = Eigen::Index(want);
    for (auto& col : cols_) {
      if (col.store) col.values.conservativeResize(capacity_);  // realloc: no copy when mapped
    }
  }

  void add_row(std::string_view text, long number, std::uint64_t end) {
    detail::split_fields(text, sep_, strip_, fields_);
    if (fields_.size() != names_.size()) {
      throw InputError(source_, number, "",
                       fmt::format("expected {} fields, found {}", names_.size(), fields_.size()));
    }
    if (rows_ == 0) first_data_line_ = number;
    if (rows_ == capacity_) grow(end);
    const bool first_row = rows_ == 0;
    for (std::size_t c = 0; c < fields_.size(); ++c) {
      ColumnState& col = cols_[c];
      double v = std::numeric_limits<double>::quiet_NaN();
      const CellStatus status = detail::parse_cell(fields_[c], v);
      if (status == CellStatus::kOk) {
        if (col.store) col.values[rows_] = v;
        if (first_row) col.first_value = v;
        continue;
      }
      if (status == CellStatus::kEmpty) {
        if (first_row) col.first_row_empty = true;
        if (col.first_empty_line == 0) col.first_empty_line = number;
        ++col.empty_count;
      } else if (col.first_bad_line == 0) {
        col.first_bad_line = number;
        col.bad_text = std::string(fields_[c]);
        col.bad_status = status;
      }
      if (col.store) col.stop_storing();
    }
    ++rows_;
  }

  // A first-row-only column (MATLAB writes Ts and fs that way).
  bool is_scalar(const ColumnState& col) const {
    return rows_ >= 2 && !col.first_row_empty && col.first_bad_line == 0 &&
           col.empty_count == long(rows_) - 1;
  }

  // The values of a checked column, moved out (shrunk to the rows, in place) or copied when
  // the same column is asked for twice.
  Eigen::VectorXd take(std::size_t c, const Recording& rec) {
    ColumnState& col = cols_[c];
    if (col.taken_at >= 0) return rec.columns[std::size_t(col.taken_at)];
    if (!col.store) throw std::logic_error("recording reader: a kept column was not stored");
    col.values.conservativeResize(rows_);
    return std::move(col.values);
  }

  void keep_columns(Recording& rec) {
    std::vector<std::size_t> keep = requested_;
    const bool all = options_.columns.empty();
    for (std::size_t c = 0; c < names_.size(); ++c) {
      const bool requested = std::find(keep.begin(), keep.end(), c) != keep.end();
      if (is_scalar(cols_[c]) && !requested) {
        rec.scalars[names_[c]] = cols_[c].first_value;
        cols_[c].stop_storing();
        continue;
      }
      const bool is_time = !rec.time_s && has_header_ && is_time_name(names_[c]) && !requested;
      if (!all && !requested && !is_time) continue;
      check_column(cols_[c], names_[c], source_);
      if (is_time) {
        rec.time_s = take(c, rec);
        rec.time_name = names_[c];
      }
    }
    if (all) {
      for (std::size_t c = 0; c < names_.size(); ++c) {
        if (!rec.scalars.count(names_[c]) && names_[c] != rec.time_name) keep.push_back(c);
      }
    }
    for (std::size_t c : keep) {
      rec.names.push_back(names_[c]);
      rec.columns.push_back(take(c, rec));
      if (cols_[c].taken_at < 0) cols_[c].taken_at = long(rec.columns.size()) - 1;
    }
  }

  std::string source_;
  const ReadOptions& options_;
  std::uint64_t size_hint_ = 0;
  bool started_ = false;
  char sep_ = 0;
  bool strip_ = false;
  bool has_header_ = false;
  std::vector<std::string> names_;
  std::vector<std::size_t> requested_;
  std::vector<ColumnState> cols_;
  std::vector<std::string_view> fields_;  // reused for every line
  Eigen::Index rows_ = 0;
  Eigen::Index capacity_ = 0;
  long first_data_line_ = 1;
  std::uint64_t data_begin_ = 0;
};

// Cuts text fed in pieces into lines: line numbers, "\r\n", blank lines (trailing ones are
// dropped, one followed by data is an error), the length bound, and an unterminated last line.
class LineSplitter {
 public:
  LineSplitter(const std::string& source, TableBuilder& table) : source_(source), table_(table) {}

  // Hands every complete line of `text` (which starts at file offset `offset`) to the table;
  // returns the bytes used. The rest is the start of a line whose end is still to come; it
  // is an error once it is longer than kMaxLineBytes.
  std::size_t feed(std::string_view text, std::uint64_t offset) {
    std::size_t pos = 0;
    while (pos < text.size()) {
      const void* nl = std::memchr(text.data() + pos, '\n', text.size() - pos);
      if (!nl) break;
      const std::size_t end = std::size_t(static_cast<const char*>(nl) - text.data());
      line(text.substr(pos, end - pos), true, offset + pos, offset + end + 1);
      pos = end + 1;
    }
    check_length(text.size() - pos, number_ + 1);
    return pos;
  }

  // At the end of the file: `rest` is what follows the last line end. Returns the number of
  // an unterminated last line that was dropped.
  std::optional<long> finish(std::string_view rest, std::uint64_t offset) {
    if (!rest.empty()) line(rest, false, offset, offset + rest.size());
    return partial_;
  }

  long next_line_number() const { return number_ + 1; }

 private:
  void check_length(std::size_t bytes, long number) const {
    if (bytes > kMaxLineBytes) {
      throw InputError(source_, number, "",
                       fmt::format("expected lines of at most {} KiB ({} bytes), found a longer "
                                   "one (binary data, or no line ends?)",
                                   kMaxLineBytes / 1024, kMaxLineBytes));
    }
  }

  void line(std::string_view text, bool terminated, std::uint64_t begin, std::uint64_t end) {
    ++number_;
    check_length(text.size(), number_);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    if (is_blank(text)) {
      if (!pending_blank_) pending_blank_ = number_;
      return;
    }
    if (!terminated) {
      partial_ = number_;  // the writer always ends a row with '\n'
      return;
    }
    if (pending_blank_ && table_.started()) {
      throw InputError(source_, *pending_blank_, "", "expected a data row, found a blank line");
    }
    pending_blank_.reset();
    table_.add_line(text, number_, begin, end);
  }

  const std::string& source_;
  TableBuilder& table_;
  long number_ = 0;
  std::optional<long> pending_blank_;
  std::optional<long> partial_;
};

// Bytes of a byte-order mark at the start: a UTF-8 one (EF BB BF, written by Excel and
// Notepad) is skipped; a UTF-16 one means the numbers are not ASCII, which is refused.
std::size_t byte_order_mark(std::string_view head, const std::string& source) {
  if (head.substr(0, 3) == "\xEF\xBB\xBF") return 3;
  if (head.substr(0, 2) == "\xFF\xFE" || head.substr(0, 2) == "\xFE\xFF") {
    throw InputError(source, 1, "",
                     "expected UTF-8 or ASCII text, found UTF-16 (a byte-order mark FF FE or "
                     "FE FF): save the file as UTF-8");
  }
  return 0;
}

Recording parse_table(std::string_view text, const std::string& source,
                      const ReadOptions& options) {
  TableBuilder table(source, options, text.size());
  LineSplitter lines(source, table);
  const std::size_t bom = byte_order_mark(text, source);
  const std::size_t used = lines.feed(text.substr(bom), bom);
  return table.finish(lines.finish(text.substr(bom + used), bom + used));
}

Recording read_table(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string source = path.string();
  InputFile file(path, "a recording");
  TableBuilder table(source, options, file.size());
  LineSplitter lines(source, table);
  // A pending (incomplete) line is at most kMaxLineBytes, so the buffer never grows.
  std::vector<char> buffer(kMaxLineBytes + kChunkBytes);
  std::size_t have = 0;      // bytes in the buffer
  std::uint64_t offset = 0;  // file offset of buffer[0]
  bool at_start = true;
  bool eof = false;
  while (!eof) {
    const std::size_t got = file.read(buffer.data() + have, buffer.size() - have);
    eof = got == 0;
    have += got;
    std::size_t start = 0;
    if (at_start) {
      if (have < 3 && !eof) continue;  // the byte-order mark is judged on 3 bytes
      start = byte_order_mark(std::string_view(buffer.data(), have), source);
      at_start = false;
    }
    const std::string_view text(buffer.data() + start, have - start);
    if (eof) {
      const std::size_t used = lines.feed(text, offset + start);
      return table.finish(lines.finish(text.substr(used), offset + start + used));
    }
    const std::size_t used = start + lines.feed(text, offset + start);
    std::memmove(buffer.data(), buffer.data() + used, have - used);
    have -= used;
    offset += used;
  }
  throw std::logic_error("recording reader: unreachable");
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

Recording parse_recording(std::string_view text, const std::string& source,
                          const ReadOptions& options) {
  Recording rec = parse_table(text, source, options);
  resolve_time_base(rec, options);
  return rec;
}

Recording read_recording(const std::filesystem::path& path, const ReadOptions& options) {
  Recording rec = read_table(path, options);
  const std::filesystem::path side = sidecar_path(path);
  std::error_code ec;
  if (options.read_sidecar && side != path && std::filesystem::exists(side, ec)) {
    rec.sidecar = read_sidecar(side);
  }
  resolve_time_base(rec, options);
  return rec;
}

}  // namespace rig::io
