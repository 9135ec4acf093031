#include "rig/session/cpu_latency.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cstdint>

namespace rig::session {

bool CpuLatencyHold::acquire() {
  if (fd_ >= 0) return true;
  const int fd = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const std::int32_t latency_us = 0;
  if (::write(fd, &latency_us, sizeof latency_us) != static_cast<ssize_t>(sizeof latency_us)) {
    ::close(fd);
    return false;
  }
  fd_ = fd;  // the request stays in force while the file is open
  return true;
}

void CpuLatencyHold::release() {
  if (fd_ < 0) return;
  ::close(fd_);
  fd_ = -1;
}

}  // namespace rig::session
