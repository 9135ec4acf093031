// While a realtime test runs, the rig asks the kernel to keep every CPU out of deep idle
// states (Linux PM QoS: /dev/cpu_dma_latency held open with 0 us written, as cyclictest
// does). A CPU that has gone idle between two ticks otherwise wakes late, and on a virtual
// machine an idle virtual CPU may wait for its host: on a 2-vCPU host the exchange with a
// co-located plantsim had a p99 of 0.6-2.6 ms and a max of 7-15 ms without the hold, and
// 0.12-0.13 ms and 0.9-2.1 ms with it (docs/decisions.md). Best effort, like SCHED_FIFO: it
// needs root; the report says whether it was held. Released on destruction.
#pragma once

namespace rig::session {

class CpuLatencyHold {
 public:
  CpuLatencyHold() = default;
  ~CpuLatencyHold() { release(); }
  CpuLatencyHold(const CpuLatencyHold&) = delete;
  CpuLatencyHold& operator=(const CpuLatencyHold&) = delete;

  // Requests a 0 us wake-up latency; true when the request is in force.
  bool acquire();
  void release();
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

}  // namespace rig::session
