// CpuLatencyHold (rig/session/cpu_latency.hpp): while held, the kernel's CPU latency target,
// read back from /dev/cpu_dma_latency, is 0 us; once released it is what it was before.
#include "rig/session/cpu_latency.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <optional>

namespace rig::session {
namespace {

constexpr const char* kDevice = "/dev/cpu_dma_latency";

// The latency target in force (us), as the device reads back; nullopt when unreadable.
std::optional<std::int32_t> latency_target_us() {
  const int fd = ::open(kDevice, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::int32_t value = -1;
  const bool ok = ::read(fd, &value, sizeof value) == static_cast<ssize_t>(sizeof value);
  ::close(fd);
  return ok ? std::optional(value) : std::nullopt;
}

TEST(CpuLatencyHold, HoldsTheLatencyTargetAtZeroUntilReleased) {
  if (::access(kDevice, W_OK) != 0) GTEST_SKIP() << kDevice << " is not writable (not root)";
  const auto before = latency_target_us();
  ASSERT_TRUE(before.has_value());
  if (*before == 0) GTEST_SKIP() << "another process already holds the target at 0 us";
  {
    CpuLatencyHold hold;
    EXPECT_FALSE(hold.held());
    ASSERT_TRUE(hold.acquire());
    EXPECT_TRUE(hold.held());
    EXPECT_TRUE(hold.acquire()) << "a second acquire keeps the one request";
    EXPECT_EQ(latency_target_us(), 0);
    hold.release();
    EXPECT_FALSE(hold.held());
    EXPECT_EQ(latency_target_us(), before);
    ASSERT_TRUE(hold.acquire());
    EXPECT_EQ(latency_target_us(), 0);
  }
  EXPECT_EQ(latency_target_us(), before) << "the destructor releases the request";
}

}  // namespace
}  // namespace rig::session
