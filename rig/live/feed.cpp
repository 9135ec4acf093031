#include "rig/live/feed.hpp"

#include <algorithm>

namespace rig::live {

void Feed::publish(std::string_view kind, const nlohmann::json& body) {
  auto m = std::make_shared<Message>();
  m->kind = std::string(kind);
  // A NaN has no JSON form; dump() would write null, which the readers treat as missing.
  m->json = body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  {
    const std::lock_guard lock(mutex_);
    if (closed_) return;
    m->seq = ++seq_;
    MessagePtr stored = std::move(m);
    latest_[stored->kind] = stored;
    if (!superseded_by_next(stored->kind)) {
      messages_.push_back(std::move(stored));
      if (messages_.size() > kMaxMessages) thin_locked();
    }
  }
  cv_.notify_all();
}

// Every other "sample" of the older half goes; if that freed too little (a feed of events
// only), the oldest quarter goes.
void Feed::thin_locked() {
  const std::size_t half = messages_.size() / 2;
  std::deque<MessagePtr> kept;
  bool drop = false;
  for (std::size_t i = 0; i < messages_.size(); ++i) {
    const MessagePtr& m = messages_[i];
    if (i < half && m->kind == kind::kSample) {
      drop = !drop;
      if (drop) continue;
    }
    kept.push_back(m);
  }
  if (kept.size() > kMaxMessages * 7 / 8) kept.erase(kept.begin(), kept.begin() + kept.size() / 4);
  messages_ = std::move(kept);
}

void Feed::close() {
  {
    const std::lock_guard lock(mutex_);
    closed_ = true;
  }
  cv_.notify_all();
}

bool Feed::superseded_by_next(std::string_view k) {
  return k == kind::kState || k == kind::kTiming || k == kind::kBode;
}

std::vector<MessagePtr> Feed::since(std::uint64_t after, std::size_t max_count) const {
  const std::lock_guard lock(mutex_);
  auto first = std::upper_bound(messages_.begin(), messages_.end(), after,
                                [](std::uint64_t s, const MessagePtr& m) { return s < m->seq; });
  const auto left = static_cast<std::size_t>(messages_.end() - first);
  const std::size_t n = std::min(max_count, left);
  std::vector<MessagePtr> out(first, first + static_cast<std::ptrdiff_t>(n));
  // The latest of each superseded kind, in order, but not beyond a batch cut short (the
  // reader's next `after` must not skip the history it has not read yet).
  const std::uint64_t limit = n < left && !out.empty() ? out.back()->seq : seq_;
  for (const char* k : {kind::kState, kind::kTiming, kind::kBode}) {
    const auto it = latest_.find(k);
    if (it != latest_.end() && it->second->seq > after && it->second->seq <= limit) {
      out.push_back(it->second);
    }
  }
  std::sort(out.begin(), out.end(),
            [](const MessagePtr& a, const MessagePtr& b) { return a->seq < b->seq; });
  return out;
}

bool Feed::wait(std::uint64_t after, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  cv_.wait_for(lock, timeout, [&] { return seq_ > after || closed_; });
  return seq_ > after;
}

MessagePtr Feed::latest(std::string_view kind) const {
  const std::lock_guard lock(mutex_);
  const auto it = latest_.find(kind);
  return it == latest_.end() ? nullptr : it->second;
}

std::uint64_t Feed::last_seq() const {
  const std::lock_guard lock(mutex_);
  return seq_;
}

bool Feed::closed() const {
  const std::lock_guard lock(mutex_);
  return closed_;
}

std::size_t Feed::size() const {
  const std::lock_guard lock(mutex_);
  return messages_.size();
}

}  // namespace rig::live
