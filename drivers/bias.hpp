// The bias command's wire value, shared by the Modbus (holding 0) and CAN (PGN 0xFF50) maps:
// int16, 0.001 % of rated power per bit. Quantising in one place keeps both links identical.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

namespace drivers {

inline constexpr double kBiasPctPerBit = 0.001;

// raw = round(bias_pct / 0.001), clamped to int16 (+-32.767 %); NaN maps to 0 (no bias).
inline std::int16_t quantise_bias(double bias_pct) {
  if (std::isnan(bias_pct)) return 0;
  const double raw = std::round(bias_pct / kBiasPctPerBit);
  constexpr double lo = std::numeric_limits<std::int16_t>::min();
  constexpr double hi = std::numeric_limits<std::int16_t>::max();
  return static_cast<std::int16_t>(raw < lo ? lo : (raw > hi ? hi : raw));
}

inline double bias_from_raw(std::int16_t raw) { return raw * kBiasPctPerBit; }

}  // namespace drivers
