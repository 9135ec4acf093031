// J1939 frame codecs for the CAN map of DESIGN.md section 6. Pure functions over
// `struct can_frame` (29-bit identifiers, data little-endian), shared by the rig's CAN link
// and plantsim's CAN node. drivers/README.md gives the reasons for the choices below.
//
// Identifier (29 bits): priority (3) | EDP (1) | DP (1) | PF (8) | PS (8) | SA (8).
// PDU1 (PF < 240): PS is the destination address and is not part of the PGN.
// PDU2 (PF >= 240): PS is the group extension and belongs to the PGN.
//
// Messages (priority in brackets; unused bytes and reserved bits are sent as 1):
//   TSC1  PGN 0      [3] rig -> governor  byte 0 bits 0-1 override control mode (01 speed
//                    control, 00 no override = release), bits 4-5 override priority (11 low),
//                    bytes 1-2 requested speed 0.125 rpm/bit (0xFFFF when releasing), byte 3
//                    torque limit (0xFF), byte 7 low nibble counter, high nibble checksum.
//   EEC1  PGN 61444  [3] governor -> rig  byte 2 actual torque 1 %/bit -125, bytes 3-4 engine
//                    speed 0.125 rpm/bit, byte 5 source address of the controlling device
//                    (the rig's address while its bias is applied, else the governor's own).
//   GTACP PGN 65029  [6] governor -> rig  bytes 0-3 real power 1 W/bit offset -2e9,
//                    bytes 4-7 reactive power 1 var/bit offset -2e9.
//   0xFF50 rig command [3]  bytes 0-1 bias SLOT (below), byte 2 bits 0-1 external bias
//                    enable state (00 disable, 01 enable, 10 error, 11 don't care = keep),
//                    bits 2-7 = 1, bytes 3-6 0xFF, byte 7 high nibble counter, low nibble
//                    checksum. The counter is the heartbeat: +1 (mod 16) on every frame.
//   0xFF51 plant sample [6]  bytes 0-3 power (GTACP scaling), bytes 4-5 sample counter uint16
//                    (+1 per plant tick), byte 6 status (StatusBit), byte 7 high nibble =
//                    sample counter mod 16, low nibble checksum.
//   0xFF52 lockstep [6] (sim only)  bytes 0-1 ticks to advance uint16, bytes 2-7 0xFF. The
//                    plant advances exactly that many ticks, then sends one 0xFF51.
//   0xFF53 bias echo [6]  governor -> rig, one per accepted 0xFF50 or TSC1, sent at the plant
//                    tick the command takes effect: bytes 0-1 bias applied (SLOT, after the
//                    governor's clamp, 0 when disabled or the heartbeat is lost), bytes 2-3
//                    bias received (SLOT, before the clamp), bytes 4-5 sample counter of that
//                    tick, byte 6 status (StatusBit), byte 7 high nibble = the counter of the
//                    command answered, low nibble checksum.
//
// Bias SLOT (bytes 0-1 of 0xFF50, 0-1 and 2-3 of 0xFF53): offset binary like every J1939
// 2-byte parameter, 0.001 %/bit, offset -32 %: bias_pct = raw * 0.001 - 32.000, so raw 32000
// is 0 %, the valid range 0x0000..0xFAFF is -32.000 .. +32.255 %, and 0xFB00..0xFFFF (J1939's
// reserved, error and "not available" ranges) never encode a bias.
//
// Checksum (J1939-71 SPN 3689 style, 4 bits), over the identifier so that a frame from the
// wrong sender or with a corrupted id fails too:
//   s  = data[0] + ... + data[6] + (counter & 0x0F) + id[7:0] + id[15:8] + id[23:16] + id[28:24]
//   cs = ((s >> 4) + s) & 0x0F
#pragma once

#include <linux/can.h>

#include <cstdint>
#include <optional>

#include "drivers/governor_link.hpp"

namespace drivers::j1939 {

// Source addresses.
inline constexpr std::uint8_t kGovernorAddress = 0x00;  // J1939 "engine #1"
inline constexpr std::uint8_t kRigAddress = 0xF9;       // J1939 "off-board service tool #1"
inline constexpr std::uint8_t kGlobalAddress = 0xFF;

// Priorities: 3 for control (TSC1 and EEC1 as J1939-71; 0xFF50 like TSC1), 6 for the rest
// (GTACP as J1939-71; J1939-21's default for proprietary B data).
inline constexpr std::uint8_t kPriorityControl = 3;
inline constexpr std::uint8_t kPriorityData = 6;

// Parameter group numbers.
inline constexpr std::uint32_t kPgnTsc1 = 0;
inline constexpr std::uint32_t kPgnEec1 = 61444;   // 0xF004
inline constexpr std::uint32_t kPgnGtacp = 65029;  // 0xFE05
inline constexpr std::uint32_t kPgnRigCommand = 0xFF50;
inline constexpr std::uint32_t kPgnPlantSample = 0xFF51;
inline constexpr std::uint32_t kPgnLockstep = 0xFF52;
inline constexpr std::uint32_t kPgnBiasEcho = 0xFF53;

// Scalings.
inline constexpr double kSpeedRpmPerBit = 0.125;
inline constexpr double kPowerOffsetW = -2.0e9;  // physical = raw * 1 W + offset
inline constexpr double kBiasPctPerBit = 0.001;
inline constexpr double kBiasOffsetPct = -32.0;       // physical = raw * 0.001 % + offset
inline constexpr std::uint16_t kBiasRawMax = 0xFAFF;  // +32.255 %

// Bias SLOT: clamped to -32.000 .. +32.255 %, rounded to 0.001 %; NaN encodes 0 %.
std::uint16_t encode_bias(double bias_pct);
// nullopt for raw values above 0xFAFF (J1939 reserved / error / not available).
std::optional<double> decode_bias(std::uint16_t raw);
// What the governor receives for `bias_pct`: decode_bias(encode_bias(bias_pct)).
double quantise_bias_slot(double bias_pct);

struct Id {
  std::uint8_t priority = kPriorityData;  // 0 (highest) .. 7
  std::uint32_t pgn = 0;                  // 18 bits
  std::uint8_t source = 0;
  std::uint8_t destination = kGlobalAddress;  // PDU1 only
};

bool is_pdu1(std::uint32_t pgn);
std::uint32_t encode_id(const Id& id);  // 29-bit identifier, without CAN_EFF_FLAG
Id decode_id(std::uint32_t id29);
std::uint8_t checksum4(const std::uint8_t* data7, std::uint8_t counter, std::uint32_t id29);

// Decoded messages in engineering units.
struct Tsc1 {
  double speed_rpm = 0.0;
  std::uint8_t counter = 0;  // 0..15
  bool release = false;      // override control mode 00: the override ends, speed ignored
};
struct Eec1 {
  double speed_rpm = 0.0;
  double actual_torque_pct = 0.0;
  std::uint8_t controlling_address = kGovernorAddress;
};
struct Gtacp {
  double real_power_w = 0.0;
  double reactive_power_var = 0.0;
};
struct RigCommand {
  double bias_pct = 0.0;  // the SLOT's 0.001 %, clamped to -32.000 .. +32.255 %
  bool enable = false;
  std::uint8_t counter = 0;  // 0..15, +1 per frame
  bool keep_enable = false;  // enable state 11 "don't care": the governor keeps its state
};
struct PlantSample {
  double power_w = 0.0;
  std::uint16_t counter = 0;
  std::uint8_t status = 0;  // drivers::StatusBit
};
struct Lockstep {
  std::uint16_t ticks = 0;
};
struct BiasEcho {
  double applied_pct = 0.0;
  double received_pct = 0.0;
  std::uint16_t sample_counter = 0;
  std::uint8_t status = 0;           // drivers::StatusBit
  std::uint8_t command_counter = 0;  // 0..15: the 0xFF50 / TSC1 counter answered
};

can_frame encode_tsc1(const Tsc1& m, std::uint8_t source = kRigAddress,
                      std::uint8_t destination = kGovernorAddress);
can_frame encode_eec1(const Eec1& m, std::uint8_t source = kGovernorAddress);
can_frame encode_gtacp(const Gtacp& m, std::uint8_t source = kGovernorAddress);
can_frame encode_rig_command(const RigCommand& m, std::uint8_t source = kRigAddress);
can_frame encode_plant_sample(const PlantSample& m, std::uint8_t source = kGovernorAddress);
can_frame encode_lockstep(const Lockstep& m, std::uint8_t source = kRigAddress);
can_frame encode_bias_echo(const BiasEcho& m, std::uint8_t source = kGovernorAddress);

// Decoders check: extended 29-bit data frame, DLC 8, the PGN, the checksum, and (when
// `previous_counter` is given) that the counter is previous + 1 mod 16. Errors are kProtocol
// (length, frame type, PGN, value not available or error indicator) or kChecksum (checksum,
// counter), with `where` = "PGN 0x....". The priority is not checked (J1939 receivers may not
// rely on it).
LinkResult<Tsc1> decode_tsc1(const can_frame& f,
                             std::optional<std::uint8_t> previous_counter = std::nullopt);
LinkResult<Eec1> decode_eec1(const can_frame& f);
LinkResult<Gtacp> decode_gtacp(const can_frame& f);
LinkResult<RigCommand> decode_rig_command(
    const can_frame& f, std::optional<std::uint8_t> previous_counter = std::nullopt);
LinkResult<PlantSample> decode_plant_sample(const can_frame& f);
LinkResult<Lockstep> decode_lockstep(const can_frame& f);
LinkResult<BiasEcho> decode_bias_echo(const can_frame& f);

// PGN and source address of a frame (0xFFFFFFFF for a standard/RTR/error frame).
std::uint32_t pgn_of(const can_frame& f);
std::uint8_t source_of(const can_frame& f);

}  // namespace drivers::j1939
