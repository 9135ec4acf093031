// The live feed of a running test or monitor (docs/live.md): what the tick loop publishes for
// the live page (--http) and the fleet feed (--mqtt) to read on their own threads.
//
// The loop's side is publish(): it serialises one small JSON object and appends it under a
// mutex held for the append only, so a slow or stalled reader (a browser, a broker) can never
// block a tick. Readers take shared pointers to the stored messages in batches and write them
// out after releasing the lock.
//
// History: so that a page opened mid-test can draw the test so far, every message is kept,
// except the kinds a newer message supersedes (state, timing, bode: only the latest of each is
// kept), up to kMaxMessages; beyond that the older half's "sample" messages are thinned to
// every other one (a monitor running for days keeps its recent past at full resolution and
// the rest at a resolution that halves with age) and, past that, the oldest messages go.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace rig::live {

// Message kinds (docs/live.md lists each body).
namespace kind {
inline constexpr const char* kStart = "start";             // command, set id, band, rate
inline constexpr const char* kState = "state";             // phase, progress, supervisor, estimates
inline constexpr const char* kSample = "sample";           // power deviation and excitation, ~10 Hz
inline constexpr const char* kEvent = "event";             // phase change, trip, warning, link
inline constexpr const char* kEstimate = "estimate";       // one block estimate with its errors
inline constexpr const char* kBode = "bode";               // the latest model's frequency response
inline constexpr const char* kSweepPoint = "sweep_point";  // one swept-sine point
inline constexpr const char* kAlarm = "alarm";             // rig monitor: a named fault
inline constexpr const char* kTrend = "trend";             // rig monitor: one block's parameters
inline constexpr const char* kTrendHistory = "trend_history";  // rig monitor: earlier runs
inline constexpr const char* kAlarmHistory = "alarm_history";  // rig monitor: earlier runs
inline constexpr const char* kTiming = "timing";               // loop timing so far
inline constexpr const char* kOutcome = "outcome";             // exit code and one-line outcome
}  // namespace kind

struct Message {
  std::uint64_t seq = 0;  // 1, 2, ... in publication order; gaps where history was thinned
  std::string kind;
  std::string json;  // the body, serialised once
};
using MessagePtr = std::shared_ptr<const Message>;

class Feed {
 public:
  // About 2.5 h of samples at 10 Hz with the rest, 9 MB: what a browser takes in well
  // under a second on a page opened late.
  static constexpr std::size_t kMaxMessages = 100000;
  static constexpr std::size_t kMaxBatch = 2000;  // messages copied per lock

  // Loop side. Cheap: one dump of `body` and an append.
  void publish(std::string_view kind, const nlohmann::json& body);
  // No more messages (the command is ending): wakes every waiting reader.
  void close();

  // Kinds of which only the latest message matters (kept out of the history).
  static bool superseded_by_next(std::string_view kind);

  // Reader side. Messages with seq > after, oldest first, at most max_count (of a
  // superseded kind only the latest, when it is newer than `after`).
  std::vector<MessagePtr> since(std::uint64_t after, std::size_t max_count = kMaxBatch) const;
  // Waits until a message with seq > after exists, the feed closes, or timeout passes;
  // true when there is something new to read.
  bool wait(std::uint64_t after, std::chrono::milliseconds timeout) const;
  // The newest message of a kind (a retained "last state"), null when none.
  MessagePtr latest(std::string_view kind) const;
  std::uint64_t last_seq() const;
  bool closed() const;
  std::size_t size() const;

 private:
  void thin_locked();

  mutable std::mutex mutex_;
  mutable std::condition_variable cv_;
  std::deque<MessagePtr> messages_;
  std::map<std::string, MessagePtr, std::less<>> latest_;
  std::uint64_t seq_ = 0;
  bool closed_ = false;
};

}  // namespace rig::live
