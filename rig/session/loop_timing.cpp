#include "rig/session/loop_timing.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rig::session {
namespace {

// Bins of a "round" width (1, 2 or 5 x 10^k ms) so that at most 60 cover [0, max].
TimingHistogram histogram(const std::vector<float>& values_ms) {
  TimingHistogram h;
  if (values_ms.empty()) return h;
  const double max_ms = *std::max_element(values_ms.begin(), values_ms.end());
  const double raw = std::max(max_ms / 60.0, 1e-3);
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  h.bin_ms = 10.0 * decade;
  for (double step : {1.0, 2.0, 5.0}) {
    if (raw <= step * decade) {
      h.bin_ms = step * decade;
      break;
    }
  }
  const auto bins = static_cast<std::size_t>(std::floor(max_ms / h.bin_ms)) + 1;
  h.counts.assign(bins, 0.0);
  for (float v : values_ms) {
    const auto i = static_cast<std::size_t>(std::max(0.0, std::floor(v / h.bin_ms)));
    h.counts[std::min(i, bins - 1)] += 1.0;
  }
  return h;
}

// Largest value of each whole second of test time.
void per_second_max(const std::vector<float>& t_s, const std::vector<float>& v_ms,
                    std::vector<double>& out_t, std::vector<double>& out_max) {
  const std::size_t n = std::min(t_s.size(), v_ms.size());
  for (std::size_t i = 0; i < n; ++i) {
    const double second = std::floor(t_s[i]);
    if (out_t.empty() || out_t.back() != second) {
      out_t.push_back(second);
      out_max.push_back(v_ms[i]);
    } else {
      out_max.back() = std::max(out_max.back(), static_cast<double>(v_ms[i]));
    }
  }
}

double mean(const std::vector<float>& v) {
  if (v.empty()) return 0.0;
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

}  // namespace

double quantile_ms(std::vector<float> values, double q) {
  if (values.empty()) return 0.0;
  // Nearest rank: the smallest value with at least q N values at or below it.
  const auto n = values.size();
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
  const std::size_t k = std::min(n - 1, rank == 0 ? 0 : rank - 1);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

LoopTimer::LoopTimer(bool realtime, double period_s) : realtime_(realtime), period_s_(period_s) {}

void LoopTimer::trim() {
  if (window_ == 0 || t_s_.size() <= 2 * window_) return;
  auto drop = [this](std::vector<float>& v) {
    v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(std::min(window_, v.size())));
  };
  drop(t_s_);
  drop(lateness_ms_);
  drop(exchange_ms_);
  dropped_ += window_;
}

void LoopTimer::start(double t_s, double lateness_s, bool overrun, bool slip) {
  trim();
  t_s_.push_back(static_cast<float>(t_s));
  if (!realtime_) return;
  lateness_ms_.push_back(static_cast<float>(1e3 * std::max(0.0, lateness_s)));
  if (overrun) ++overruns_;
  if (slip) {
    ++slips_;
    slip_total_s_ += lateness_s;
  }
}

void LoopTimer::exchange(double wall_s) {
  exchange_ms_.push_back(static_cast<float>(1e3 * wall_s));
}

std::vector<float> LoopTimer::last(std::size_t n) const {
  const std::vector<float>& v = realtime_ ? lateness_ms_ : exchange_ms_;
  const std::size_t k = std::min(n, v.size());
  return {v.end() - static_cast<std::ptrdiff_t>(k), v.end()};
}

LoopTimer::Recent LoopTimer::recent(std::size_t n) const {
  const std::vector<float> v = last(n);
  return {quantile_ms(v, 0.5), quantile_ms(v, 0.99), quantile_ms(v, 1.0)};
}

LoopTimingSummary LoopTimer::summary() const {
  LoopTimingSummary s;
  s.mode = realtime_ ? "realtime" : "lockstep";
  s.period_ms = 1e3 * period_s_;
  s.cycles = t_s_.size() + dropped_;
  s.exchange_p50_ms = quantile_ms(exchange_ms_, 0.5);
  s.exchange_p99_ms = quantile_ms(exchange_ms_, 0.99);
  s.exchange_max_ms = quantile_ms(exchange_ms_, 1.0);
  s.exchange_mean_ms = mean(exchange_ms_);
  const std::vector<float>& charted = realtime_ ? lateness_ms_ : exchange_ms_;
  if (realtime_) {
    s.jitter_p50_ms = quantile_ms(lateness_ms_, 0.5);
    s.jitter_p99_ms = quantile_ms(lateness_ms_, 0.99);
    s.jitter_max_ms = quantile_ms(lateness_ms_, 1.0);
    s.jitter_mean_ms = mean(lateness_ms_);
    s.overruns = overruns_;
    s.realtime_priority = fifo_;
    s.cpu_latency_held = cpu_latency_held_;
    s.slips = slips_;
    s.slip_total_ms = 1e3 * slip_total_s_;
  }
  s.histogram = histogram(charted);
  per_second_max(t_s_, charted, s.second_t_s, s.second_max_ms);
  return s;
}

}  // namespace rig::session
