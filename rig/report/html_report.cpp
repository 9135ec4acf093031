#include "rig/report/html_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "rig/io/atomic_file.hpp"
#include "rig/report/uplot_assets.hpp"

namespace rig::report {
namespace {

using nlohmann::json;

constexpr const char* kPageCss = R"css(
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:24px auto;max-width:1100px;
  color:#222;padding:0 16px}
h1{font-size:1.6em;border-bottom:2px solid #345;padding-bottom:6px}
h2{font-size:1.25em;margin-top:1.8em;color:#345}
table{border-collapse:collapse;margin:8px 0}
td,th{border:1px solid #ccc;padding:3px 10px;text-align:right;font-variant-numeric:tabular-nums}
th{background:#eef2f6}
td:first-child,th:first-child{text-align:left}
tr.hl td{background:#fff6d8;font-weight:600}
table.kv td:first-child{color:#555}
.note{padding:8px 12px;margin:8px 0;border-left:5px solid #888;background:#f5f5f5}
.note.ok{border-color:#2a7;background:#eefaf3}.note.warning{border-color:#d90;background:#fff8e5}
.note.fatal{border-color:#c22;background:#fdecec}.note.info{border-color:#38c;background:#eef6fc}
.chart{margin:12px 0;min-height:60px}
)css";

// Builds uPlot options from each chart's JSON block and draws it; records the outcome on
// <body> so that a headless browser test can check it.
constexpr const char* kDrawJs = R"js(
(function () {
  var palette = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#17becf"];
  function fail(message) { document.body.setAttribute("data-js-error", String(message)); }
  window.addEventListener("error", function (e) { fail(e.message || e); });
  function draw(node) {
    var c = JSON.parse(node.textContent);
    var target = document.getElementById(node.getAttribute("data-chart"));
    var series = [{ label: c.x_label }];
    c.series.forEach(function (s, i) {
      series.push({ label: s.label, stroke: s.color || palette[i % palette.length],
                    width: s.width, dash: s.dashed ? [6, 4] : undefined,
                    points: { show: s.points }, spanGaps: false });
    });
    var opts = {
      title: c.title, width: Math.max(320, target.clientWidth || 900), height: c.height,
      scales: { x: { time: false, distr: c.log_x ? 3 : 1, log: 10 },
                y: { distr: c.log_y ? 3 : 1, log: 10 } },
      axes: [{ label: c.x_label }, { label: c.y_label }],
      series: series,
      bands: c.bands.map(function (b) { return { series: [b.upper + 1, b.lower + 1], fill: b.fill }; })
    };
    new uPlot(opts, [c.x].concat(c.y), target);
  }
  try {
    var nodes = document.querySelectorAll("script[data-chart]");
    for (var i = 0; i < nodes.length; ++i) draw(nodes[i]);
    document.body.setAttribute("data-charts-drawn", String(nodes.length));
  } catch (e) { fail(e && e.message ? e.message : e); }
})();
)js";

// Finite values as numbers, the rest (gaps) as null; on a log axis also values <= 0.
json values(const std::vector<double>& v, bool log_axis) {
  json out = json::array();
  for (double x : v) {
    if (std::isfinite(x) && (!log_axis || x > 0.0)) {
      out.push_back(x);
    } else {
      out.push_back(nullptr);
    }
  }
  return out;
}

void validate(const Chart& c) {
  for (const Series& s : c.series) {
    if (s.y.size() != c.x.size()) {
      throw std::invalid_argument(fmt::format("chart \"{}\": series \"{}\" has {} values for {} x",
                                              c.title, s.label, s.y.size(), c.x.size()));
    }
  }
  for (double x : c.x) {
    if (!std::isfinite(x) || (c.log_x && x <= 0.0)) {
      throw std::invalid_argument(fmt::format("chart \"{}\": x must be finite{}", c.title,
                                              c.log_x ? " and > 0 on a log axis" : ""));
    }
  }
  for (const Band& b : c.bands) {
    if (b.upper >= c.series.size() || b.lower >= c.series.size()) {
      throw std::invalid_argument(fmt::format("chart \"{}\": band names a missing series", c.title));
    }
  }
}

// JSON that is safe inside <script>: '<' only occurs inside strings, where \u003c is valid.
std::string script_safe(const json& doc) {
  std::string text = doc.dump();
  std::string out;
  out.reserve(text.size());
  for (char ch : text) {
    if (ch == '<') {
      out += "\\u003c";
    } else {
      out += ch;
    }
  }
  return out;
}

}  // namespace

std::string escape_html(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char ch : text) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += ch;
    }
  }
  return out;
}

HtmlReport::HtmlReport(std::string title) : title_(std::move(title)) {}

HtmlReport& HtmlReport::section(const std::string& heading) {
  body_ += "<h2>" + escape_html(heading) + "</h2>\n";
  return *this;
}

HtmlReport& HtmlReport::paragraph(const std::string& text) {
  body_ += "<p>" + escape_html(text) + "</p>\n";
  return *this;
}

HtmlReport& HtmlReport::note(Tone tone, const std::string& text) {
  static constexpr const char* kClass[] = {"info", "ok", "warning", "fatal"};
  body_ += fmt::format("<div class=\"note {}\">{}</div>\n", kClass[static_cast<int>(tone)],
                       escape_html(text));
  return *this;
}

HtmlReport& HtmlReport::key_values(const std::vector<std::pair<std::string, std::string>>& rows) {
  body_ += "<table class=\"kv\">\n";
  for (const auto& [key, value] : rows) {
    body_ += "<tr><td>" + escape_html(key) + "</td><td>" + escape_html(value) + "</td></tr>\n";
  }
  body_ += "</table>\n";
  return *this;
}

HtmlReport& HtmlReport::table(const Table& t) {
  body_ += "<table>\n<tr>";
  for (const auto& h : t.header) body_ += "<th>" + escape_html(h) + "</th>";
  body_ += "</tr>\n";
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (t.rows[r].size() != t.header.size()) {
      throw std::invalid_argument(fmt::format("table row {} has {} cells for {} columns", r,
                                              t.rows[r].size(), t.header.size()));
    }
    const bool hl = std::find(t.highlight_rows.begin(), t.highlight_rows.end(), r) !=
                    t.highlight_rows.end();
    body_ += hl ? "<tr class=\"hl\">" : "<tr>";
    for (const auto& cell : t.rows[r]) body_ += "<td>" + escape_html(cell) + "</td>";
    body_ += "</tr>\n";
  }
  body_ += "</table>\n";
  return *this;
}

HtmlReport& HtmlReport::chart(const Chart& c) {
  validate(c);
  json doc = {{"title", c.title}, {"x_label", c.x_label}, {"y_label", c.y_label},
              {"log_x", c.log_x}, {"log_y", c.log_y},     {"height", c.height_px},
              {"x", values(c.x, c.log_x)}};
  json series = json::array(), ys = json::array(), bands = json::array();
  for (const Series& s : c.series) {
    series.push_back({{"label", s.label}, {"color", s.color}, {"dashed", s.dashed},
                      {"points", s.points}, {"width", s.width_px}});
    ys.push_back(values(s.y, c.log_y));
  }
  for (const Band& b : c.bands) bands.push_back({{"upper", b.upper}, {"lower", b.lower}, {"fill", b.fill}});
  doc["series"] = series;
  doc["y"] = ys;
  doc["bands"] = bands;
  const std::string id = fmt::format("chart-{}", charts_++);
  body_ += fmt::format("<div class=\"chart\" id=\"{}\"></div>\n", id);
  chart_data_ += fmt::format("<script type=\"application/json\" data-chart=\"{}\">{}</script>\n",
                             id, script_safe(doc));
  return *this;
}

std::string HtmlReport::render() const {
  std::string page;
  page.reserve(kUplotJs.size() + kUplotCss.size() + body_.size() + chart_data_.size() + 4096);
  page += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>";
  page += escape_html(title_);
  page += "</title>\n<style>\n";
  page += kUplotCss;
  page += kPageCss;
  page += "</style>\n<script>\n";
  page += kUplotJs;
  page += "\n</script>\n</head>\n";
  page += fmt::format("<body data-charts-expected=\"{}\">\n<h1>{}</h1>\n", charts_,
                      escape_html(title_));
  page += body_;
  page += chart_data_;
  page += "<script>";
  page += kDrawJs;
  page += "</script>\n</body>\n</html>\n";
  return page;
}

void HtmlReport::write(const std::filesystem::path& path) const {
  io::write_file_atomic(path, render());
}

}  // namespace rig::report
