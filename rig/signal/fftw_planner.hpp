// FFTW's planner (fftw_plan_*, fftw_destroy_plan) is not thread-safe; fftw_execute on distinct
// plans is. Every part of the rig that plans FFTs locks this one mutex around planning, so
// correlators, FRF estimation and tests may run on different threads.
#pragma once

#include <mutex>

namespace rig::signal {

std::mutex& fftw_planner_mutex();

}  // namespace rig::signal
