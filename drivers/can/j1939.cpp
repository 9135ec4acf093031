#include "drivers/can/j1939.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace drivers::j1939 {
namespace {

constexpr std::uint32_t kRawMax16 = 0xFAFF;      // J1939 largest valid 2-byte value
constexpr std::uint32_t kRawMax32 = 0xFAFFFFFF;  // J1939 largest valid 4-byte value
constexpr int kBiasZeroRaw = 32000;              // -kBiasOffsetPct / kBiasPctPerBit

std::string pgn_text(std::uint32_t pgn) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "PGN 0x%04X", static_cast<unsigned>(pgn));
  return buf;
}

LinkError codec_error(LinkErrorKind kind, std::uint32_t pgn, std::string detail) {
  return LinkError{kind, pgn_text(pgn), std::move(detail)};
}

can_frame blank_frame(const Id& id) {
  can_frame f{};
  f.can_id = encode_id(id) | CAN_EFF_FLAG;
  f.can_dlc = 8;
  std::fill(std::begin(f.data), std::end(f.data), 0xFF);  // J1939 "not available"
  return f;
}

void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t get_u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
         (std::uint32_t{p[3]} << 24);
}

std::uint32_t scale_clamped(double value, double per_bit, double offset, std::uint32_t max) {
  const double raw = std::round((value - offset) / per_bit);
  if (!(raw > 0.0)) return 0;  // also NaN
  return raw >= max ? max : static_cast<std::uint32_t>(raw);
}

// Common checks: extended data frame, DLC 8, expected PGN.
LinkResult<void> check_frame(const can_frame& f, std::uint32_t pgn) {
  if (!(f.can_id & CAN_EFF_FLAG) || (f.can_id & (CAN_RTR_FLAG | CAN_ERR_FLAG))) {
    return codec_error(LinkErrorKind::kProtocol, pgn, "expected an extended 29-bit data frame");
  }
  if (f.can_dlc != 8) {
    return codec_error(LinkErrorKind::kProtocol, pgn,
                       "expected 8 data bytes, got " + std::to_string(f.can_dlc));
  }
  if (pgn_of(f) != pgn) {
    return codec_error(LinkErrorKind::kProtocol, pgn, "frame carries " + pgn_text(pgn_of(f)));
  }
  return {};
}

LinkResult<void> check_sum_and_counter(const can_frame& f, std::uint32_t pgn, std::uint8_t counter,
                                       std::uint8_t checksum,
                                       std::optional<std::uint8_t> previous) {
  const std::uint8_t expected = checksum4(f.data, counter, f.can_id & CAN_EFF_MASK);
  if (checksum != expected) {
    return codec_error(
        LinkErrorKind::kChecksum, pgn,
        "checksum " + std::to_string(checksum) + ", expected " + std::to_string(expected));
  }
  if (previous && counter != ((*previous + 1) & 0x0F)) {
    return codec_error(LinkErrorKind::kChecksum, pgn,
                       "counter " + std::to_string(counter) + " after " +
                           std::to_string(*previous) + ", expected " +
                           std::to_string((*previous + 1) & 0x0F));
  }
  return {};
}

// Enable state of 0xFF50 byte 2 bits 0-1 (the J1939 2-bit state parameter).
constexpr std::uint8_t kStateOff = 0b00;
constexpr std::uint8_t kStateOn = 0b01;
constexpr std::uint8_t kStateError = 0b10;
constexpr std::uint8_t kStateDontCare = 0b11;

// A bias SLOT at data[at..at+1]; kProtocol for the reserved, error and not-available ranges.
LinkResult<double> bias_field(const can_frame& f, int at, std::uint32_t pgn, const char* what) {
  const std::uint16_t raw = get_u16(&f.data[at]);
  const auto bias = decode_bias(raw);
  if (!bias) {
    char buf[80];
    std::snprintf(buf, sizeof buf, "%s 0x%04X is not a value (J1939 %s)", what, raw,
                  raw >= 0xFF00 ? "not available" : (raw >= 0xFE00 ? "error" : "reserved"));
    return codec_error(LinkErrorKind::kProtocol, pgn, buf);
  }
  return *bias;
}

// Byte 7 layout of the proprietary frames: counter in the high nibble, checksum in the low.
void seal_high_counter(can_frame& f, std::uint8_t counter) {
  counter &= 0x0F;
  f.data[7] = static_cast<std::uint8_t>((counter << 4) |
                                        checksum4(f.data, counter, f.can_id & CAN_EFF_MASK));
}

}  // namespace

// raw = round(bias / 0.001) + 32000: the same rounding as the Modbus map (drivers/bias.hpp),
// so both links put the same 0.001 % step on the wire.
std::uint16_t encode_bias(double bias_pct) {
  if (std::isnan(bias_pct)) return kBiasZeroRaw;
  const double raw = std::round(bias_pct / kBiasPctPerBit) + kBiasZeroRaw;
  if (!(raw > 0.0)) return 0;
  return raw >= kBiasRawMax ? kBiasRawMax : static_cast<std::uint16_t>(raw);
}

std::optional<double> decode_bias(std::uint16_t raw) {
  if (raw > kBiasRawMax) return std::nullopt;
  // Integer steps first, so that raw 32000 is exactly 0 %.
  return (static_cast<int>(raw) - kBiasZeroRaw) * kBiasPctPerBit;
}

double quantise_bias_slot(double bias_pct) { return *decode_bias(encode_bias(bias_pct)); }

bool is_pdu1(std::uint32_t pgn) { return ((pgn >> 8) & 0xFF) < 240; }

std::uint32_t encode_id(const Id& id) {
  std::uint32_t pgn = id.pgn & 0x3FFFF;
  if (is_pdu1(pgn)) pgn = (pgn & 0x3FF00) | id.destination;
  return (std::uint32_t{id.priority & 0x7u} << 26) | (pgn << 8) | id.source;
}

Id decode_id(std::uint32_t id29) {
  Id id;
  id.priority = static_cast<std::uint8_t>((id29 >> 26) & 0x7);
  id.source = static_cast<std::uint8_t>(id29 & 0xFF);
  const std::uint32_t pgn = (id29 >> 8) & 0x3FFFF;
  if (is_pdu1(pgn)) {
    id.destination = static_cast<std::uint8_t>(pgn & 0xFF);
    id.pgn = pgn & 0x3FF00;
  } else {
    id.destination = kGlobalAddress;
    id.pgn = pgn;
  }
  return id;
}

std::uint8_t checksum4(const std::uint8_t* data7, std::uint8_t counter, std::uint32_t id29) {
  std::uint32_t s = counter & 0x0Fu;
  for (int i = 0; i < 7; ++i) s += data7[i];
  for (int i = 0; i < 4; ++i) s += (id29 >> (8 * i)) & 0xFFu;
  return static_cast<std::uint8_t>(((s >> 4) + s) & 0x0Fu);
}

std::uint32_t pgn_of(const can_frame& f) {
  if (!(f.can_id & CAN_EFF_FLAG) || (f.can_id & (CAN_RTR_FLAG | CAN_ERR_FLAG))) {
    return 0xFFFFFFFFu;
  }
  return decode_id(f.can_id & CAN_EFF_MASK).pgn;
}

std::uint8_t source_of(const can_frame& f) { return static_cast<std::uint8_t>(f.can_id & 0xFF); }

// ---- TSC1 ----------------------------------------------------------------------------------

can_frame encode_tsc1(const Tsc1& m, std::uint8_t source, std::uint8_t destination) {
  can_frame f = blank_frame(Id{kPriorityControl, kPgnTsc1, source, destination});
  // Byte 0: override control mode 01 (speed control) or 00 (no override: release), speed
  // conditions 00, override priority 11 (low), bits 6-7 reserved (11). Releasing leaves the
  // speed "not available" (0xFFFF).
  f.data[0] = m.release ? 0b11'11'00'00 : 0b11'11'00'01;
  if (!m.release) {
    put_u16(&f.data[1], static_cast<std::uint16_t>(
                            scale_clamped(m.speed_rpm, kSpeedRpmPerBit, 0.0, kRawMax16)));
  }
  const std::uint8_t counter = m.counter & 0x0F;
  f.data[7] = static_cast<std::uint8_t>((checksum4(f.data, counter, f.can_id & CAN_EFF_MASK) << 4) |
                                        counter);
  return f;
}

LinkResult<Tsc1> decode_tsc1(const can_frame& f, std::optional<std::uint8_t> previous_counter) {
  if (auto r = check_frame(f, kPgnTsc1); !r) return r.error();
  const std::uint8_t counter = f.data[7] & 0x0F;
  if (auto r = check_sum_and_counter(f, kPgnTsc1, counter, f.data[7] >> 4, previous_counter); !r) {
    return r.error();
  }
  const int mode = f.data[0] & 0x03;
  if (mode == 0x00) return Tsc1{0.0, counter, true};
  if (mode != 0x01) {
    return codec_error(LinkErrorKind::kProtocol, kPgnTsc1,
                       "override mode " + std::to_string(mode) +
                           ", expected 1 (speed control) or 0 (no override)");
  }
  const std::uint16_t raw = get_u16(&f.data[1]);
  if (raw > kRawMax16) {
    return codec_error(LinkErrorKind::kProtocol, kPgnTsc1, "requested speed not available");
  }
  return Tsc1{raw * kSpeedRpmPerBit, counter, false};
}

// ---- EEC1 ----------------------------------------------------------------------------------

can_frame encode_eec1(const Eec1& m, std::uint8_t source) {
  can_frame f = blank_frame(Id{kPriorityControl, kPgnEec1, source, kGlobalAddress});
  f.data[2] = static_cast<std::uint8_t>(scale_clamped(m.actual_torque_pct, 1.0, -125.0, 250));
  put_u16(&f.data[3],
          static_cast<std::uint16_t>(scale_clamped(m.speed_rpm, kSpeedRpmPerBit, 0.0, kRawMax16)));
  f.data[5] = m.controlling_address;
  return f;
}

LinkResult<Eec1> decode_eec1(const can_frame& f) {
  if (auto r = check_frame(f, kPgnEec1); !r) return r.error();
  const std::uint16_t raw = get_u16(&f.data[3]);
  if (raw > kRawMax16) {
    return codec_error(LinkErrorKind::kProtocol, kPgnEec1, "engine speed not available");
  }
  return Eec1{raw * kSpeedRpmPerBit, f.data[2] <= 250 ? f.data[2] - 125.0 : 0.0, f.data[5]};
}

// ---- GTACP ---------------------------------------------------------------------------------

can_frame encode_gtacp(const Gtacp& m, std::uint8_t source) {
  can_frame f = blank_frame(Id{kPriorityData, kPgnGtacp, source, kGlobalAddress});
  put_u32(&f.data[0], scale_clamped(m.real_power_w, 1.0, kPowerOffsetW, kRawMax32));
  put_u32(&f.data[4], scale_clamped(m.reactive_power_var, 1.0, kPowerOffsetW, kRawMax32));
  return f;
}

LinkResult<Gtacp> decode_gtacp(const can_frame& f) {
  if (auto r = check_frame(f, kPgnGtacp); !r) return r.error();
  const std::uint32_t p = get_u32(&f.data[0]);
  const std::uint32_t q = get_u32(&f.data[4]);
  if (p > kRawMax32) {
    return codec_error(LinkErrorKind::kProtocol, kPgnGtacp, "real power not available");
  }
  return Gtacp{p + kPowerOffsetW, q > kRawMax32 ? 0.0 : q + kPowerOffsetW};
}

// ---- 0xFF50 rig command --------------------------------------------------------------------

can_frame encode_rig_command(const RigCommand& m, std::uint8_t source) {
  can_frame f = blank_frame(Id{kPriorityControl, kPgnRigCommand, source, kGlobalAddress});
  put_u16(&f.data[0], encode_bias(m.bias_pct));
  const std::uint8_t state = m.keep_enable ? kStateDontCare : (m.enable ? kStateOn : kStateOff);
  f.data[2] = static_cast<std::uint8_t>(0xFC | state);
  seal_high_counter(f, m.counter);
  return f;
}

LinkResult<RigCommand> decode_rig_command(const can_frame& f,
                                          std::optional<std::uint8_t> previous_counter) {
  if (auto r = check_frame(f, kPgnRigCommand); !r) return r.error();
  const std::uint8_t counter = f.data[7] >> 4;
  if (auto r =
          check_sum_and_counter(f, kPgnRigCommand, counter, f.data[7] & 0x0F, previous_counter);
      !r) {
    return r.error();
  }
  auto bias = bias_field(f, 0, kPgnRigCommand, "bias");
  if (!bias) return bias.error();
  const std::uint8_t state = f.data[2] & 0x03;
  if (state == kStateError) {
    return codec_error(LinkErrorKind::kProtocol, kPgnRigCommand, "enable state 10 (error)");
  }
  return RigCommand{*bias, state == kStateOn, counter, state == kStateDontCare};
}

// ---- 0xFF51 plant sample -------------------------------------------------------------------

can_frame encode_plant_sample(const PlantSample& m, std::uint8_t source) {
  can_frame f = blank_frame(Id{kPriorityData, kPgnPlantSample, source, kGlobalAddress});
  put_u32(&f.data[0], scale_clamped(m.power_w, 1.0, kPowerOffsetW, kRawMax32));
  put_u16(&f.data[4], m.counter);
  f.data[6] = m.status;
  seal_high_counter(f, static_cast<std::uint8_t>(m.counter & 0x0F));
  return f;
}

LinkResult<PlantSample> decode_plant_sample(const can_frame& f) {
  if (auto r = check_frame(f, kPgnPlantSample); !r) return r.error();
  const std::uint16_t counter = get_u16(&f.data[4]);
  const std::uint8_t nibble = f.data[7] >> 4;
  if (auto r = check_sum_and_counter(f, kPgnPlantSample, nibble, f.data[7] & 0x0F, {}); !r) {
    return r.error();
  }
  if (nibble != (counter & 0x0F)) {
    return codec_error(LinkErrorKind::kChecksum, kPgnPlantSample,
                       "byte 7 counter " + std::to_string(nibble) +
                           " disagrees with sample counter " + std::to_string(counter));
  }
  const std::uint32_t p = get_u32(&f.data[0]);
  if (p > kRawMax32) {
    return codec_error(LinkErrorKind::kProtocol, kPgnPlantSample, "power not available");
  }
  return PlantSample{p + kPowerOffsetW, counter, f.data[6]};
}

// ---- 0xFF52 lockstep -----------------------------------------------------------------------

can_frame encode_lockstep(const Lockstep& m, std::uint8_t source) {
  can_frame f = blank_frame(Id{kPriorityData, kPgnLockstep, source, kGlobalAddress});
  put_u16(&f.data[0], m.ticks);
  return f;
}

LinkResult<Lockstep> decode_lockstep(const can_frame& f) {
  if (auto r = check_frame(f, kPgnLockstep); !r) return r.error();
  return Lockstep{get_u16(&f.data[0])};
}

// ---- 0xFF53 bias echo ----------------------------------------------------------------------

can_frame encode_bias_echo(const BiasEcho& m, std::uint8_t source) {
  can_frame f = blank_frame(Id{kPriorityData, kPgnBiasEcho, source, kGlobalAddress});
  put_u16(&f.data[0], encode_bias(m.applied_pct));
  put_u16(&f.data[2], encode_bias(m.received_pct));
  put_u16(&f.data[4], m.sample_counter);
  f.data[6] = m.status;
  seal_high_counter(f, m.command_counter);
  return f;
}

LinkResult<BiasEcho> decode_bias_echo(const can_frame& f) {
  if (auto r = check_frame(f, kPgnBiasEcho); !r) return r.error();
  const std::uint8_t counter = f.data[7] >> 4;
  if (auto r = check_sum_and_counter(f, kPgnBiasEcho, counter, f.data[7] & 0x0F, {}); !r) {
    return r.error();
  }
  auto applied = bias_field(f, 0, kPgnBiasEcho, "bias applied");
  if (!applied) return applied.error();
  auto received = bias_field(f, 2, kPgnBiasEcho, "bias received");
  if (!received) return received.error();
  return BiasEcho{*applied, *received, get_u16(&f.data[4]), f.data[6], counter};
}

}  // namespace drivers::j1939
