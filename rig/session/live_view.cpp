#include "rig/session/live_view.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace rig::session {

std::string deviation_bar(double deviation_pct, double band_pct, int width) {
  width = std::max(width, 5) | 1;  // odd, so zero has a centre cell
  const int half = width / 2;
  std::string bar(static_cast<std::size_t>(width), '-');
  bar[static_cast<std::size_t>(half)] = '|';
  const double x = band_pct > 0.0 ? deviation_pct / band_pct : 0.0;
  if (!std::isfinite(x)) bar.assign(static_cast<std::size_t>(width), '?');
  if (!std::isfinite(x)) {
  } else if (x < -1.0) {
    bar.front() = '<';
  } else if (x > 1.0) {
    bar.back() = '>';
  } else {
    const int cell = half + static_cast<int>(std::lround(x * half));
    bar[static_cast<std::size_t>(cell)] = '#';
  }
  std::string framed;
  framed.reserve(bar.size() + 2);
  framed.push_back('[');
  framed.append(bar);
  framed.push_back(']');
  return framed;
}

namespace {
std::string clock(double s) {
  if (!std::isfinite(s) || s < 0.0) return "--:--";
  const long total = std::lround(s);
  return fmt::format("{:02d}:{:02d}", total / 60, total % 60);
}
}  // namespace

std::string format_status(const LiveStatus& s) {
  std::string line = fmt::format(
      "{:<12} {} ETA {}  dP {:+6.2f}% {} pk {:4.2f}/{:.1f}%  u {:+5.2f}%", s.phase,
      clock(s.elapsed_s), s.eta_s ? clock(*s.eta_s) : "--:--", s.deviation_pct,
      deviation_bar(s.deviation_pct, s.band_pct, 21), s.peak_deviation_pct, s.band_pct, s.bias_pct);
  for (const auto& e : s.estimates) {
    line += e.std_error > 0.0 ? fmt::format("  {} {:.4g}+-{:.2g}", e.name, e.value, e.std_error)
                              : fmt::format("  {} {:.4g}", e.name, e.value);
  }
  if (!s.flags.empty()) {
    line += "  !";
    for (const auto& f : s.flags) line += " " + f;
  }
  return line;
}

LiveView::LiveView(std::FILE* out, bool tty, double interval_s, double min_wall_s)
    : out_(out), tty_(tty), interval_s_(interval_s), min_wall_s_(min_wall_s) {}

bool LiveView::is_terminal(std::FILE* out) { return out != nullptr && isatty(fileno(out)) != 0; }

void LiveView::update(const LiveStatus& status, bool force) {
  if (out_ == nullptr) return;
  if (!force && status.elapsed_s - last_s_ < interval_s_) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && std::chrono::duration<double>(now - last_wall_).count() < min_wall_s_) return;
  last_s_ = status.elapsed_s;
  last_wall_ = now;
  if (tty_) {
    // \r then clear to end of line, so a shorter line leaves no residue.
    fmt::print(out_, "\r{}\x1b[K", format_status(status));
    line_open_ = true;
  } else {
    fmt::print(out_, "{}\n", format_status(status));
  }
  std::fflush(out_);
}

void LiveView::message(const std::string& line) {
  if (out_ == nullptr) return;
  if (line_open_) fmt::print(out_, "\r\x1b[K");
  line_open_ = false;
  fmt::print(out_, "{}\n", line);
  std::fflush(out_);
}

void LiveView::finish() {
  if (out_ != nullptr && line_open_) {
    fmt::print(out_, "\n");
    std::fflush(out_);
  }
  line_open_ = false;
}

}  // namespace rig::session
