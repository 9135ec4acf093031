// Worker threads of a realtime test (block estimates, phase-change work) are started by the
// tick loop's thread, which runs under SCHED_FIFO; a new thread inherits that policy. A
// worker calls this first so that its tens of milliseconds of arithmetic run at normal
// priority and can never hold the loop thread or the plant's threads off a core.
#pragma once

#include <pthread.h>
#include <sched.h>

namespace rig::session {

inline void use_normal_priority() {
  sched_param param{};
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &param);
}

}  // namespace rig::session
