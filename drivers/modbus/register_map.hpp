// The Modbus register map of DESIGN.md section 6: one definition shared by the rig's client
// and plantsim's server (as libmodbus's own tests share one header between both ends).
// Holding registers are read with function 03 and written with 06/16; input registers with 04.
#pragma once

#include <cstdint>

namespace drivers::modbus_map {

// Holding registers (rig -> governor).
inline constexpr int kHoldBias = 0;          // int16, 0.001 % of rated power per bit
inline constexpr int kHoldHeartbeat = 1;     // uint16, +1 on every rig write
inline constexpr int kHoldControl = 2;       // bit 0: enable external bias
inline constexpr int kHoldLockstepTicks = 100;  // sim only: ticks to advance (write N)
inline constexpr int kHoldingCount = 101;    // registers 0..100 exist; others answer exception 02

inline constexpr std::uint16_t kControlEnableBias = 1u << 0;

// Input registers (governor -> rig).
inline constexpr int kInPowerHi = 0;   // int32 W, high word first (regs 0-1)
inline constexpr int kInPowerLo = 1;
inline constexpr int kInSpeed = 2;     // uint16, 0.1 rpm
inline constexpr int kInFreq = 3;      // uint16, 0.001 Hz
inline constexpr int kInVoltage = 4;   // uint16, 1 V
inline constexpr int kInBiasEcho = 5;  // int16, 0.001 %
inline constexpr int kInStatus = 6;    // drivers::StatusBit flags
inline constexpr int kInTimeHi = 7;    // uint32 ms, high word first (regs 7-8)
inline constexpr int kInTimeLo = 8;
inline constexpr int kInCounter = 9;   // uint16, +1 per plant tick
inline constexpr int kInputCount = 10;

// Input 0-1 value meaning "power not available" (a real reading saturates above it).
inline constexpr std::int32_t kPowerNotAvailable = INT32_MIN;

// Scalings.
inline constexpr double kBiasPctPerBit = 0.001;
inline constexpr double kSpeedRpmPerBit = 0.1;
inline constexpr double kFreqHzPerBit = 0.001;
inline constexpr double kVoltsPerBit = 1.0;

// Heartbeat rule: the governor drops the bias to zero when the heartbeat register has not
// changed for this long (plus at most one plant tick).
inline constexpr int kHeartbeatTimeoutMs = 500;

inline constexpr int kDefaultUnit = 1;
inline constexpr int kDefaultTcpPort = 1502;

}  // namespace drivers::modbus_map
