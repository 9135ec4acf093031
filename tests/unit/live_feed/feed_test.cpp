#include "rig/live/feed.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace rig::live {
namespace {

using namespace std::chrono_literals;

TEST(LiveFeed, ReadersGetEveryMessageInOrderAfterTheirLastSeq) {
  Feed feed;
  for (int i = 0; i < 5; ++i) feed.publish(kind::kSample, {{"i", i}});
  const auto all = feed.since(0);
  ASSERT_EQ(all.size(), 5u);
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i]->seq, i + 1);
    EXPECT_EQ(nlohmann::json::parse(all[i]->json)["i"], static_cast<int>(i));
  }
  const auto rest = feed.since(3);
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_EQ(rest.front()->seq, 4u);
  EXPECT_EQ(feed.since(3, 1).size(), 1u);  // batches are bounded
  EXPECT_TRUE(feed.since(5).empty());
}

TEST(LiveFeed, LatestOfAKindIsKeptForPagesOpenedLater) {
  Feed feed;
  EXPECT_EQ(feed.latest(kind::kState), nullptr);
  feed.publish(kind::kState, {{"phase", "steady"}});
  feed.publish(kind::kSample, {{"t_s", 1.0}});
  feed.publish(kind::kState, {{"phase", "pilot"}});
  ASSERT_NE(feed.latest(kind::kState), nullptr);
  EXPECT_EQ(nlohmann::json::parse(feed.latest(kind::kState)->json)["phase"], "pilot");
}

// State, timing and Bode messages are superseded by the next one: a reader that follows
// the feed gets each of them, a page opened later only the latest, in sequence order, and
// never one past a batch that was cut short.
TEST(LiveFeed, SupersededKindsKeepOnlyTheLatestInTheHistory) {
  Feed feed;
  std::uint64_t follower = 0;
  int states_followed = 0;
  for (int i = 0; i < 4; ++i) {
    feed.publish(kind::kSample, {{"i", i}});
    feed.publish(kind::kState, {{"i", i}});
    for (const auto& m : feed.since(follower)) {
      states_followed += m->kind == kind::kState ? 1 : 0;
      follower = m->seq;
    }
  }
  EXPECT_EQ(states_followed, 4);
  const auto late = feed.since(0);
  ASSERT_EQ(late.size(), 5u);  // 4 samples and the last state
  EXPECT_EQ(late.back()->kind, kind::kState);
  EXPECT_EQ(nlohmann::json::parse(late.back()->json)["i"], 3);
  for (std::size_t i = 1; i < late.size(); ++i) EXPECT_LT(late[i - 1]->seq, late[i]->seq);
  const auto cut = feed.since(0, 2);  // two samples: the state (seq 8) is after them
  ASSERT_EQ(cut.size(), 2u);
  EXPECT_EQ(cut.back()->kind, kind::kSample);
  EXPECT_EQ(feed.size(), 4u);
}

TEST(LiveFeed, NanBecomesNullAndTheMessageStaysParseable) {
  Feed feed;
  feed.publish(kind::kState, {{"x", std::nan("")}});
  EXPECT_TRUE(nlohmann::json::parse(feed.since(0)[0]->json)["x"].is_null());
}

TEST(LiveFeed, WaitWakesOnPublishAndOnClose) {
  Feed feed;
  EXPECT_FALSE(feed.wait(0, 10ms));  // nothing yet: times out
  std::thread later([&] {
    std::this_thread::sleep_for(20ms);
    feed.publish(kind::kEvent, {{"kind", "phase"}});
  });
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(feed.wait(0, 5s));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);
  later.join();
  std::thread closer([&] {
    std::this_thread::sleep_for(20ms);
    feed.close();
  });
  EXPECT_FALSE(feed.wait(feed.last_seq(), 5s));
  closer.join();
  EXPECT_TRUE(feed.closed());
  feed.publish(kind::kEvent, {});  // after close: dropped
  EXPECT_EQ(feed.last_seq(), 1u);
}

// A long run keeps its recent past at full resolution: past kMaxMessages the older half's
// samples are thinned, events are all kept, and sequence numbers stay increasing.
TEST(LiveFeed, HistoryIsBoundedByThinningOldSamples) {
  Feed feed;
  const std::size_t n = Feed::kMaxMessages + 1000;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 1000 == 0) {
      feed.publish(kind::kEvent, {{"i", i}});
    } else {
      feed.publish(kind::kSample, {{"i", i}});
    }
  }
  EXPECT_LE(feed.size(), Feed::kMaxMessages);
  EXPECT_GT(feed.size(), Feed::kMaxMessages / 2);
  std::uint64_t last = 0;
  std::size_t events = 0, read = 0;
  for (auto batch = feed.since(0); !batch.empty(); batch = feed.since(last)) {
    for (const auto& m : batch) {
      EXPECT_GT(m->seq, last);
      last = m->seq;
      events += m->kind == kind::kEvent ? 1 : 0;
      ++read;
    }
  }
  EXPECT_EQ(read, feed.size());
  EXPECT_EQ(events, (n + 999) / 1000);
  EXPECT_EQ(last, n);  // the newest is always there
}

// The publisher never waits for a reader: a reader that holds batches (a stalled browser)
// does not hold the feed's lock, so publishing goes on at full speed.
TEST(LiveFeed, ASlowReaderDoesNotSlowThePublisher) {
  Feed feed;
  std::atomic<bool> done{false};
  std::thread reader([&] {
    std::uint64_t after = 0;
    while (!done) {
      const auto batch = feed.since(after);
      if (!batch.empty()) after = batch.back()->seq;
      std::this_thread::sleep_for(50ms);  // "writing to a slow socket"
    }
  });
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 20000; ++i) feed.publish(kind::kSample, {{"t_s", i * 0.1}, {"u_pct", 0.5}});
  const double per_message_us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
      20000.0;
  done = true;
  reader.join();
  std::printf("publish: %.2f us per sample message\n", per_message_us);
  EXPECT_LT(per_message_us, 100.0);  // a tick is 10 000 us
}

}  // namespace
}  // namespace rig::live
