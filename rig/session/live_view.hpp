// Terminal live view of a running test: one status line refreshed in place (\r) on a
// terminal, periodic plain lines otherwise (logs, CI). Readable during a long test: phase,
// elapsed time and ETA, power deviation against the band as a bar, current estimates with
// their uncertainty, and data-quality flags.
#pragma once

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace rig::session {

struct LiveEstimate {
  std::string name;
  double value = 0.0;
  double std_error = 0.0;
};

struct LiveStatus {
  std::string phase;                // "steady", "pilot", "excite", "sweep 1.2 Hz", ...
  double elapsed_s = 0.0;           // test time
  std::optional<double> eta_s;      // remaining, when known
  double deviation_pct = 0.0;       // (P - P0) / P0 * 100 of the latest sample
  double peak_deviation_pct = 0.0;  // largest |deviation| in the current phase
  double band_pct = 3.0;
  double bias_pct = 0.0;
  std::vector<LiveEstimate> estimates;
  std::vector<std::string> flags;  // data-quality flags ("stale", "backoff", ...)
};

// "[-----|--#--]": the band from -band to +band, '|' at zero, '#' at the deviation ('<' or
// '>' when outside the band).
std::string deviation_bar(double deviation_pct, double band_pct, int width);
// One status line without a trailing newline.
std::string format_status(const LiveStatus& status);

class LiveView {
 public:
  // `interval_s` limits refreshes by test time, `min_wall_s` by wall time (a lockstep test
  // runs many times faster than real time); `tty` chooses \r refresh or plain lines.
  LiveView(std::FILE* out, bool tty, double interval_s, double min_wall_s = 0.0);
  static bool is_terminal(std::FILE* out);
  // Shows the status if at least interval_s has passed since the last refresh (or force).
  void update(const LiveStatus& status, bool force = false);
  // A message line (phase change, trip), printed without garbling the status line.
  void message(const std::string& line);
  void finish();

 private:
  std::FILE* out_;
  bool tty_;
  double interval_s_;
  double min_wall_s_;
  double last_s_ = -1e300;
  std::chrono::steady_clock::time_point last_wall_{};
  bool line_open_ = false;
};

}  // namespace rig::session
