#include "rig/monitor/event_shape.hpp"

#include <algorithm>
#include <cmath>

namespace rig::monitor {
namespace {

double mean(const std::vector<double>& x, long a, long b) {
  a = std::max(a, 0L);
  b = std::min(b, static_cast<long>(x.size()));
  if (b <= a) return 0.0;
  double s = 0.0;
  for (long i = a; i < b; ++i) s += x[static_cast<std::size_t>(i)];
  return s / static_cast<double>(b - a);
}

double stdev(const std::vector<double>& x, long a, long b) {
  const double m = mean(x, a, b);
  double s = 0.0;
  for (long i = a; i < b; ++i) s += (x[static_cast<std::size_t>(i)] - m) * (x[i] - m);
  return b - a > 1 ? std::sqrt(s / static_cast<double>(b - a - 1)) : 0.0;
}

// The onset: the sample after which the next jump window's mean differs most from the
// preceding window's mean.
long find_onset(const std::vector<double>& x, long from, long to, long w) {
  long best = from;
  double best_d = -1.0;
  for (long c = from; c < to; ++c) {
    const double d = std::abs(mean(x, c, c + w) - mean(x, c - w, c));
    if (d > best_d) {
      best_d = d;
      best = c;
    }
  }
  // Back up to where the move starts: the first sample of the window that already moved.
  const double pre = mean(x, best - 4 * w, best - w);
  const double post = mean(x, best, best + w);
  const double half = 0.5 * (post - pre);
  long c = best;
  while (c > best - w && std::abs(x[static_cast<std::size_t>(c - 1)] - pre) > std::abs(half)) --c;
  return c;
}

}  // namespace

const char* to_string(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kSensorStep:
      return "sensor step";
    case ShapeKind::kPowerLossRecovered:
      return "power loss recovered";
    case ShapeKind::kLevelChange:
      return "level change";
    case ShapeKind::kSlowDrift:
      return "slow drift";
    case ShapeKind::kUnclear:
      break;
  }
  return "unclear";
}

EventShape classify_shape(const std::vector<double>& x, double dt_s, long from, long to,
                          const ShapeThresholds& th) {
  auto n = [dt_s](double s) { return std::max(1L, std::lround(s / dt_s)); };
  EventShape e;
  const long len = static_cast<long>(x.size());
  if (from - n(th.pre_s) < 0 || to + n(th.final_to_s) > len || to <= from) return e;
  const long w = n(th.jump_s);
  const long c = find_onset(x, from, to, w);
  e.onset = c;
  const double pre = mean(x, c - n(th.pre_s), c - 1);
  e.noise_kw = stdev(x, c - n(th.pre_s), c - 1);
  // The jump against the level just before the onset (the slow wander of the pre-onset
  // window is not part of it).
  e.jump_kw = mean(x, c, c + w) - mean(x, c - n(th.local_pre_s), c);
  e.final_kw = mean(x, c + n(th.final_from_s), c + n(th.final_to_s)) - pre;
  const long a = n(th.extreme_avg_s);
  for (long i = c; i + a <= c + n(th.extreme_s); i += std::max(1L, a / 4)) {
    const double m = mean(x, i, i + a) - pre;
    if (std::abs(m) > std::abs(e.extreme_kw)) e.extreme_kw = m;
  }
  const double min_change = std::max(
      th.min_change_kw, th.min_change_sigmas * e.noise_kw / std::sqrt(static_cast<double>(w)));
  const double fin = std::abs(e.final_kw), ext = std::abs(e.extreme_kw);
  if (fin >= min_change && std::abs(e.jump_kw) >= th.step_share * fin &&
      ext <= th.overshoot * fin) {
    e.kind = ShapeKind::kSensorStep;
  } else if (ext >= min_change && e.extreme_kw < 0.0 && fin <= th.recovered_share * ext) {
    e.kind = ShapeKind::kPowerLossRecovered;
  } else if (fin >= min_change) {
    e.kind = ShapeKind::kLevelChange;
  }
  return e;
}

std::vector<double> cycle_average(const std::vector<double>& x, long n) {
  if (n <= 1 || x.empty()) return x;
  const long len = static_cast<long>(x.size());
  std::vector<double> prefix(x.size() + 1, 0.0);
  for (long i = 0; i < len; ++i) prefix[i + 1] = prefix[i] + x[static_cast<std::size_t>(i)];
  std::vector<double> y(x.size());
  for (long i = 0; i < len; ++i) {
    const long a = std::max(0L, i - n / 2), b = std::min(len, a + n);
    y[static_cast<std::size_t>(i)] = (prefix[b] - prefix[a]) / static_cast<double>(b - a);
  }
  return y;
}

}  // namespace rig::monitor
