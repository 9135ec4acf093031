#include "rig/model/frf_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <vector>

#include "rig/model/atomic_file.hpp"
#include "rig/model/input_error.hpp"

namespace rig::model {
namespace {

// Largest FRF file read (a few thousand points take well under a megabyte).
constexpr std::size_t kMaxFrfFileBytes = std::size_t{64} << 20;

struct Problem {
  std::size_t row = 0;
  std::string column;
  std::string expected;  // empty: no problem
};

// The rules of the header comment, per point; the first offending point.
Problem frf_problem(const Frf& frf) {
  for (std::size_t i = 0; i < frf.size(); ++i) {
    const FrfPoint& p = frf[i];
    if (!(p.freq_hz > 0.0) || !std::isfinite(p.freq_hz) ||
        (i > 0 && !(p.freq_hz > frf[i - 1].freq_hz))) {
      return {i, "freq_hz", "expected frequencies > 0 and strictly increasing"};
    }
    if (!p.valid) continue;  // an unusable point may hold anything its estimator produced
    if (!(p.mag >= 0.0) || !std::isfinite(p.mag)) {
      return {i, "mag", "expected a finite magnitude >= 0"};
    }
    if (!std::isfinite(p.phase_deg)) return {i, "phase_deg", "expected a finite phase"};
    if (!(p.coherence >= 0.0 && p.coherence <= 1.0 + 1e-9)) {
      return {i, "coherence", "expected a coherence in [0, 1]"};
    }
  }
  return {};
}

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\"");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\"");
  return s.substr(b, e - b + 1);
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

// The columns a reader needs, as indices into the header (nullopt: absent).
enum Col { kFreq, kMag, kPhase, kCoherence, kMagLo, kMagHi, kValid, kColumns };
constexpr std::array<const char*, kColumns> kNames = {"freq_hz", "mag",    "phase_deg", "coherence",
                                                      "mag_lo",  "mag_hi", "valid"};
using Layout = std::array<std::optional<std::size_t>, kColumns>;

Layout layout(const std::vector<std::string_view>& header, const std::string& source, long line) {
  Layout at;
  for (std::size_t c = 0; c < header.size(); ++c) {
    for (int k = 0; k < kColumns; ++k) {
      if (header[c] == kNames[std::size_t(k)] && !at[std::size_t(k)]) at[std::size_t(k)] = c;
    }
  }
  for (int k = kFreq; k <= kCoherence; ++k) {
    if (!at[std::size_t(k)]) {
      throw InputError(source, line, kNames[std::size_t(k)],
                       "missing column (expected freq_hz,mag,phase_deg,coherence)");
    }
  }
  if (bool(at[kMagLo]) != bool(at[kMagHi])) {
    throw InputError(source, line, at[kMagLo] ? "mag_hi" : "mag_lo",
                     "missing column (mag_lo and mag_hi come together)");
  }
  return at;
}

double number(std::string_view cell, const std::string& source, long line, const char* column) {
  const std::string text(cell);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) {
    throw InputError(source, line, column, fmt::format("expected a number, found \"{}\"", text));
  }
  return v;
}

FrfPoint point(const std::vector<std::string_view>& cells, const Layout& at,
               const std::string& source, long line) {
  auto get = [&](Col k) { return number(cells[*at[k]], source, line, kNames[k]); };
  FrfPoint p;
  p.freq_hz = get(kFreq);
  p.mag = get(kMag);
  p.phase_deg = get(kPhase);
  p.coherence = get(kCoherence);
  if (at[kMagLo]) {
    p.mag_lo = get(kMagLo);
    p.mag_hi = get(kMagHi);
  }
  if (at[kValid]) {
    const std::string_view v = cells[*at[kValid]];
    if (v != "0" && v != "1") {
      throw InputError(source, line, "valid", fmt::format("expected 0 or 1, found \"{}\"", v));
    }
    p.valid = v == "1";
  }
  return p;
}

}  // namespace

std::string frf_to_csv(const Frf& frf) {
  if (const Problem p = frf_problem(frf); !p.expected.empty()) {
    throw std::invalid_argument(fmt::format("FRF point {} {}: {}", p.row, p.column, p.expected));
  }
  const bool bands = std::any_of(frf.begin(), frf.end(), [](const FrfPoint& p) {
    return std::isfinite(p.mag_lo) || std::isfinite(p.mag_hi);
  });
  std::string text = bands ? "freq_hz,mag,phase_deg,coherence,mag_lo,mag_hi,valid\n"
                           : "freq_hz,mag,phase_deg,coherence,valid\n";
  auto out = std::back_inserter(text);
  for (const FrfPoint& p : frf) {
    // "{}" is the shortest text that reads back as the same double.
    fmt::format_to(out, "{},{},{},{}", p.freq_hz, p.mag, p.phase_deg, p.coherence);
    if (bands) fmt::format_to(out, ",{},{}", p.mag_lo, p.mag_hi);
    fmt::format_to(out, ",{}\n", p.valid ? 1 : 0);
  }
  return text;
}

Frf frf_from_csv(std::string_view text, const std::string& source) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 byte-order mark
  Frf frf;
  std::optional<Layout> at;
  std::size_t columns = 0;
  std::vector<long> lines;  // file line of each point, for the messages below
  long line = 0;
  for (std::size_t start = 0; start < text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string_view raw = trim(text.substr(start, end - start));
    start = end + 1;
    ++line;
    if (raw.empty() || raw.front() == '#') continue;
    const std::vector<std::string_view> cells = split(raw);
    if (!at) {
      at = layout(cells, source, line);
      columns = cells.size();
      continue;
    }
    if (cells.size() != columns) {
      throw InputError(
          source, line, "",
          fmt::format("expected {} cells as in the header, found {}", columns, cells.size()));
    }
    frf.push_back(point(cells, *at, source, line));
    lines.push_back(line);
  }
  if (!at) throw InputError(source, 0, "", "expected a header row (freq_hz,mag,phase_deg,...)");
  if (frf.empty()) throw InputError(source, 0, "", "expected at least one data row");
  if (const Problem p = frf_problem(frf); !p.expected.empty()) {
    throw InputError(source, lines[p.row], p.column, p.expected);
  }
  return frf;
}

Frf read_frf(const std::filesystem::path& path) {
  return frf_from_csv(read_small_input_file(path, "an FRF", kMaxFrfFileBytes), path.string());
}

void write_frf(const std::filesystem::path& path, const Frf& frf) {
  write_file_atomic(path, frf_to_csv(frf));
}

}  // namespace rig::model
