// A small builder for the one-file HTML reports every command writes (DESIGN.md section 4:
// "self-contained, viewable offline"). The page embeds the vendored uPlot script and
// stylesheet (rig/report/uplot_assets.hpp) and each chart's data as JSON, so it needs no
// network and no other file.
//
// Blocks are appended in order: section headings, paragraphs, notes (coloured callouts for
// flags), key/value blocks, tables and charts. After the page's script has drawn every
// chart it sets <body data-charts-drawn="N">; a script error sets data-js-error="message".
// Tests read those attributes from a headless browser's DOM dump.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace rig::report {

struct Series {
  std::string label;
  std::vector<double> y;  // one value per x; NaN (or <= 0 on a log axis) leaves a gap
  std::string color;      // CSS colour; empty: the next colour of the palette
  bool dashed = false;
  bool points = false;    // draw markers (for sparse measured points)
  double width_px = 1.5;
};

// A shaded area between two series (e.g. an uncertainty interval), by index into series.
struct Band {
  std::size_t upper = 0;
  std::size_t lower = 0;
  std::string fill = "rgba(31,119,180,0.18)";
};

struct Chart {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<double> x;  // increasing; > 0 when log_x
  std::vector<Series> series;
  std::vector<Band> bands;
  bool log_x = false;
  bool log_y = false;
  int height_px = 320;
};

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  // each as long as header
  std::vector<std::size_t> highlight_rows;     // e.g. the selected model order
};

enum class Tone { kInfo, kOk, kWarning, kFatal };

class HtmlReport {
 public:
  explicit HtmlReport(std::string title);

  HtmlReport& section(const std::string& heading);
  HtmlReport& paragraph(const std::string& text);
  HtmlReport& note(Tone tone, const std::string& text);
  HtmlReport& key_values(const std::vector<std::pair<std::string, std::string>>& rows);
  // std::invalid_argument when a row's length differs from the header's.
  HtmlReport& table(const Table& table);
  // std::invalid_argument when a series' length differs from x, or log_x with x <= 0, or a
  // band names a missing series.
  HtmlReport& chart(const Chart& chart);

  std::size_t chart_count() const { return charts_; }
  std::string render() const;
  // Atomic write (temporary file + rename).
  void write(const std::filesystem::path& path) const;

 private:
  std::string title_;
  std::string body_;
  std::string chart_data_;  // <script type="application/json"> blocks
  std::size_t charts_ = 0;
};

// Text with &, <, >, " and ' escaped for HTML.
std::string escape_html(const std::string& text);

}  // namespace rig::report
