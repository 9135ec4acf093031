// The one source of the safety defaults (DESIGN.md section 8). The test file's [safety] table
// (SafetySettings, docs/test-file.md) and the supervisor's own configuration (SupervisorConfig)
// both start from these, so a supervisor built with its defaults is the supervisor of a test
// file that leaves [safety] out (tests/unit/session/test_config_test.cpp checks it).
#pragma once

namespace rig::session {

// The largest power band allowed without an explicit override (DESIGN.md section 8).
inline constexpr double kStandardBandPct = 3.0;

namespace safety_defaults {

inline constexpr double kSampleRateHz = 100.0;        // [link] sample_rate_hz: the tick is 1 / this
inline constexpr double kBandPct = kStandardBandPct;  // |P - P0| <= this % of P0
inline constexpr double kPlanFraction = 0.8;          // planned peak within this share of the band
inline constexpr double kBackoffFraction = 0.9;  // the back-off scale reaches 0 here (band share)
// |bias| bound, % of rated power: a last layer, above what any plan asks (the plan's amplitude
// is capped at a third of it, docs/test-file.md), below a step that is no small signal.
inline constexpr double kClampPct = 5.0;
inline constexpr double kRampPctPerS = 2.0;            // bias ramp to baseline, % of rated per s
inline constexpr double kActivationTimeoutS = 2.0;     // the governor reports the bias active
inline constexpr double kEchoTolerancePct = 0.02;      // |echo - command|, % of rated (20 steps)
inline constexpr double kEchoRelativeTolerance = 0.1;  // plus this share of |command|
inline constexpr double kEchoDelayS = 0.05;            // the echo may show a command this old
inline constexpr double kEchoMaxBadS = 0.05;           // a mismatch lasting longer trips
// A governor counter may repeat this long before the sample is stale, the same 100 ms the
// realtime links allow (drivers::LinkOptions::stale_timeout; in lockstep the link also checks
// that the counter moved by exactly the ticks asked for). A governor, or a host, that stalls
// for a few ticks is not a dead link: three repeats at 100 Hz (30 ms) tripped on a loaded CI
// machine whose realtime plant stalled 36 ms.
inline constexpr double kStaleTimeoutS = 0.1;

// A time as whole ticks at rate_hz, rounded up (a tolerance in time is never shortened; the
// 1e-9 keeps 0.05 s at 100 Hz at 5 ticks despite rounding).
constexpr int ticks_at(double seconds, double rate_hz) {
  const double x = seconds * rate_hz - 1e-9;
  const int whole = static_cast<int>(x);
  return whole < x ? whole + 1 : whole;
}

}  // namespace safety_defaults
}  // namespace rig::session
