#include "rig/signal/streaming_correlator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "rig/signal/lag_kernels.hpp"

namespace rig::signal {
namespace {

constexpr Eigen::Index kCompactSamples = 4096;  // dead prefix tolerated before a memmove
constexpr Eigen::Index kAnchorBatch = 8;        // anchors deferred by per-sample pushes

}  // namespace

StreamingCorrelator::StreamingCorrelator(const StreamingOptions& options) : options_(options) {
  validate(options_.correlator, -1);
  if (!(options_.weight >= 1.0)) {
    throw std::invalid_argument("streaming correlator: weight W must be >= 1, got " +
                                std::to_string(options_.weight));
  }
  if (options_.block_samples < 0) {
    throw std::invalid_argument("streaming correlator: block_samples must be >= 0, got " +
                                std::to_string(options_.block_samples));
  }
  lags_ = options_.correlator.lags;
  zero_ = resolved_zero_index(options_.correlator);
  positive_ = lags_ - 1 - zero_;
  const auto reserve = static_cast<size_t>(lags_ + 2 * kCompactSamples);
  u_.reserve(reserve);
  y_.reserve(reserve);
  switch (options_.correlator.kind) {
    case CorrelatorKind::kRelay:
      u_mask_.reserve(reserve);
      break;
    case CorrelatorKind::kPolarity:
      u_neg_.reserve(reserve);
      y_neg_.reserve(reserve);
      break;
    default:
      break;
  }
  reset();
}

void StreamingCorrelator::reset() {
  u_.clear();
  y_.clear();
  u_mask_.clear();
  u_neg_.clear();
  y_neg_.clear();
  buf_start_ = received_ = 0;
  next_anchor_ = positive_;  // first anchor whose whole window is inside the record
  const auto l = static_cast<size_t>(lags_);
  sums_.uu.assign(l, 0.0);
  sums_.yu.assign(l, 0.0);
  sums_.neg_uu.assign(l, 0);
  sums_.neg_yu.assign(l, 0);
  block_products_ = block_received_ = products_ = blocks_ = 0;
  avg_uu_.setZero(lags_);
  avg_yu_.setZero(lags_);
}

void StreamingCorrelator::append(double u, double y) {
  u_.push_back(u);
  y_.push_back(y);
  if (options_.correlator.kind == CorrelatorKind::kRelay) {
    u_mask_.push_back(detail::sign_mask(u));
  } else if (options_.correlator.kind == CorrelatorKind::kPolarity) {
    u_neg_.push_back(detail::is_negative(u));
    y_neg_.push_back(detail::is_negative(y));
  }
  ++received_;
  ++block_received_;
}

void StreamingCorrelator::push(double u, double y) {
  append(u, y);
  const bool block_end = options_.block_samples > 0 && block_received_ >= options_.block_samples;
  if (block_end || ready_anchors() >= kAnchorBatch) process_ready();
  if (block_end) finish_block();
  compact();
}

void StreamingCorrelator::push(const Eigen::VectorXd& u_block, const Eigen::VectorXd& y_block) {
  if (u_block.size() != y_block.size()) {
    throw std::invalid_argument("streaming correlator: u and y blocks must be equally long, got " +
                                std::to_string(u_block.size()) + " and " +
                                std::to_string(y_block.size()));
  }
  Eigen::Index i = 0;
  while (i < u_block.size()) {
    // Process up to the end of the current averaging block, so blocks end on exact samples.
    Eigen::Index chunk = u_block.size() - i;
    if (options_.block_samples > 0) {
      chunk = std::min(chunk, options_.block_samples - block_received_);
    }
    for (Eigen::Index k = 0; k < chunk; ++k) append(u_block[i + k], y_block[i + k]);
    i += chunk;
    process_ready();
    if (options_.block_samples > 0 && block_received_ >= options_.block_samples) finish_block();
    compact();
  }
  if (options_.block_samples == 0 && u_block.size() > 0) finish_block();
}

// Anchors t >= next_anchor (every skip-th) whose window [t - P, t + z] has fully arrived.
Eigen::Index StreamingCorrelator::ready_anchors() const {
  const Eigen::Index last = received_ - 1;
  if (next_anchor_ + zero_ > last) return 0;
  return (last - zero_ - next_anchor_) / options_.correlator.skip + 1;
}

// Adds the products of `count` anchors from next_anchor into `sums`.
void StreamingCorrelator::accumulate(Eigen::Index count, Sums& sums) const {
  if (count <= 0) return;
  const detail::AnchorRun run{count, options_.correlator.skip, lags_};
  const auto a = static_cast<size_t>(next_anchor_ - buf_start_);
  const auto w = static_cast<size_t>(next_anchor_ - positive_ - buf_start_);
  switch (options_.correlator.kind) {
    case CorrelatorKind::kDirect:
      detail::direct_run2(&u_[a], &y_[a], &u_[w], run, sums.uu.data(), sums.yu.data());
      break;
    case CorrelatorKind::kFft:
      detail::fft_run(&u_[a], &u_[w], run, sums.uu.data());
      detail::fft_run(&y_[a], &u_[w], run, sums.yu.data());
      break;
    case CorrelatorKind::kRelay:
      detail::relay_run2(&u_[a], &y_[a], &u_mask_[w], run, sums.uu.data(), sums.yu.data());
      break;
    case CorrelatorKind::kPolarity:
      detail::polarity_run(&u_neg_[a], &u_neg_[w], run, sums.neg_uu.data());
      detail::polarity_run(&y_neg_[a], &u_neg_[w], run, sums.neg_yu.data());
      break;
  }
}

void StreamingCorrelator::process_ready() {
  const Eigen::Index count = ready_anchors();
  accumulate(count, sums_);
  next_anchor_ += count * options_.correlator.skip;
  block_products_ += count;
  products_ += count;
}

// Drops samples no future window needs (everything before next_anchor - P), in bulk.
void StreamingCorrelator::compact() {
  const Eigen::Index dead = next_anchor_ - positive_ - buf_start_;
  if (dead < std::max(kCompactSamples, lags_)) return;
  const auto d = static_cast<std::ptrdiff_t>(std::min<Eigen::Index>(dead, received_ - buf_start_));
  u_.erase(u_.begin(), u_.begin() + d);
  y_.erase(y_.begin(), y_.begin() + d);
  if (!u_mask_.empty()) u_mask_.erase(u_mask_.begin(), u_mask_.begin() + d);
  if (!u_neg_.empty()) u_neg_.erase(u_neg_.begin(), u_neg_.begin() + d);
  if (!y_neg_.empty()) y_neg_.erase(y_neg_.begin(), y_neg_.begin() + d);
  buf_start_ += d;
}

// Mean over sums with m products, reverse lag order; channel 0 = uu, 1 = yu.
static Eigen::VectorXd mean_of(const auto& sums, int channel, Eigen::Index m, bool polarity) {
  const auto& s = channel == 0 ? sums.uu : sums.yu;
  const auto& neg = channel == 0 ? sums.neg_uu : sums.neg_yu;
  Eigen::VectorXd r(static_cast<Eigen::Index>(s.size()));
  const auto n = static_cast<double>(m);
  for (Eigen::Index j = 0; j < r.size(); ++j) {
    const auto k = static_cast<size_t>(j);
    r[j] = polarity ? 1.0 - 2.0 * static_cast<double>(neg[k]) / n : s[k] / n;
  }
  return r;
}

void StreamingCorrelator::finish_block() {
  block_received_ = 0;
  if (block_products_ == 0) return;  // still filling the first lag window
  ++blocks_;
  if (options_.averaging == Averaging::kCumulative) return;  // sums keep running
  const bool polarity = options_.correlator.kind == CorrelatorKind::kPolarity;
  const Eigen::VectorXd uu = mean_of(sums_, 0, block_products_, polarity);
  const Eigen::VectorXd yu = mean_of(sums_, 1, block_products_, polarity);
  if (blocks_ == 1) {
    avg_uu_ = uu;
    avg_yu_ = yu;
  } else {
    avg_uu_ += (uu - avg_uu_) / options_.weight;
    avg_yu_ += (yu - avg_yu_) / options_.weight;
  }
  std::fill(sums_.uu.begin(), sums_.uu.end(), 0.0);
  std::fill(sums_.yu.begin(), sums_.yu.end(), 0.0);
  std::fill(sums_.neg_uu.begin(), sums_.neg_uu.end(), 0);
  std::fill(sums_.neg_yu.begin(), sums_.neg_yu.end(), 0);
  block_products_ = 0;
}

Correlation StreamingCorrelator::finalise(const Eigen::VectorXd& reversed) const {
  Correlation c;
  c.zero_index = zero_;
  c.dt_s = options_.correlator.dt_s;
  c.r = reversed.reverse();
  if (options_.correlator.arcsine_correction) {
    c.r = (c.r.array() * (std::numbers::pi / 2.0)).sin().matrix();
  }
  return c;
}

// Running mean of the current block (kCumulative: of everything), deferred anchors included.
Correlation StreamingCorrelator::block_mean(int channel) const {
  const Eigen::Index pending = ready_anchors();
  if (block_products_ + pending == 0) {
    throw std::logic_error("streaming correlator: no products yet (need " + std::to_string(lags_) +
                           " samples); check products() > 0");
  }
  const bool polarity = options_.correlator.kind == CorrelatorKind::kPolarity;
  if (pending == 0) return finalise(mean_of(sums_, channel, block_products_, polarity));
  Sums with_pending = sums_;
  accumulate(pending, with_pending);
  return finalise(mean_of(with_pending, channel, block_products_ + pending, polarity));
}

Correlation StreamingCorrelator::ruu() const {
  if (options_.averaging == Averaging::kExponential && blocks_ > 0) return finalise(avg_uu_);
  return block_mean(0);
}

Correlation StreamingCorrelator::ryu() const {
  if (options_.averaging == Averaging::kExponential && blocks_ > 0) return finalise(avg_yu_);
  return block_mean(1);
}

}  // namespace rig::signal
