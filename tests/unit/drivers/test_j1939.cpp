#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "drivers/bias.hpp"
#include "drivers/can/j1939.hpp"

namespace j = drivers::j1939;
using drivers::LinkErrorKind;

namespace {

std::uint32_t raw_id(const can_frame& f) { return f.can_id & CAN_EFF_MASK; }

}  // namespace

TEST(J1939Id, Pdu2KeepsGroupExtensionInPgn) {
  const std::uint32_t id = j::encode_id({3, 0xFF51, 0x00, 0x42});
  EXPECT_EQ(id, 0x0CFF5100u);  // priority 3 -> 0x0C......, destination ignored for PDU2
  const j::Id back = j::decode_id(id);
  EXPECT_EQ(back.pgn, 0xFF51u);
  EXPECT_EQ(back.priority, 3);
  EXPECT_EQ(back.source, 0x00);
  EXPECT_EQ(back.destination, j::kGlobalAddress);
}

TEST(J1939Id, Pdu1CarriesDestinationInPs) {
  const std::uint32_t id = j::encode_id({3, j::kPgnTsc1, j::kRigAddress, j::kGovernorAddress});
  EXPECT_EQ(id, 0x0C0000F9u);
  const std::uint32_t id2 = j::encode_id({6, 0xEA00, 0x11, 0x22});  // request PGN, PDU1
  EXPECT_EQ(id2, 0x18EA2211u);
  const j::Id back = j::decode_id(id2);
  EXPECT_EQ(back.pgn, 0xEA00u);
  EXPECT_EQ(back.destination, 0x22);
  EXPECT_EQ(back.source, 0x11);
  EXPECT_TRUE(j::is_pdu1(j::kPgnTsc1));
  EXPECT_FALSE(j::is_pdu1(j::kPgnEec1));
}

TEST(J1939Tsc1, WorkedExample750Rpm) {
  const can_frame f = j::encode_tsc1({750.0, 5});
  EXPECT_EQ(f.data[1], 0x70);  // raw 6000 = 0x1770, little-endian
  EXPECT_EQ(f.data[2], 0x17);
  EXPECT_EQ(f.data[0] & 0x03, 0x01);  // speed-control mode
  EXPECT_EQ(j::pgn_of(f), j::kPgnTsc1);
  auto d = j::decode_tsc1(f, std::uint8_t{4});
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_DOUBLE_EQ(d->speed_rpm, 750.0);
  EXPECT_EQ(d->counter, 5);
  EXPECT_FALSE(d->release);
}

// Override control mode 00 ("no override") ends the override; the speed is "not available".
TEST(J1939Tsc1, ReleaseIsOverrideMode00) {
  const can_frame f = j::encode_tsc1({600.0, 6, true});
  EXPECT_EQ(f.data[0], 0xF0);  // mode 00, conditions 00, priority 11, reserved 11
  EXPECT_EQ(f.data[1], 0xFF);
  EXPECT_EQ(f.data[2], 0xFF);
  auto d = j::decode_tsc1(f, std::uint8_t{5});
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_TRUE(d->release);
  EXPECT_EQ(d->counter, 6);
  // Torque control (mode 10) is not something this governor takes.
  can_frame torque = j::encode_tsc1({600.0, 0});
  torque.data[0] = 0xF2;
  torque.data[7] =
      static_cast<std::uint8_t>((j::checksum4(torque.data, 0, raw_id(torque)) << 4) | 0);
  auto t = j::decode_tsc1(torque);
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error().kind, LinkErrorKind::kProtocol);
}

TEST(J1939Gtacp, WorkedExample4p6Mw) {
  const can_frame f = j::encode_gtacp({4.6e6, 0.0});
  EXPECT_EQ(f.data[0], 0xC0);  // raw 0x777BC4C0 = 4.6e6 + 2e9
  EXPECT_EQ(f.data[1], 0xC4);
  EXPECT_EQ(f.data[2], 0x7B);
  EXPECT_EQ(f.data[3], 0x77);
  auto d = j::decode_gtacp(f);
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_DOUBLE_EQ(d->real_power_w, 4.6e6);
  EXPECT_DOUBLE_EQ(d->reactive_power_var, 0.0);
}

TEST(J1939Eec1, RoundTripSpeedAndControllingAddress) {
  const can_frame f = j::encode_eec1({600.375, 80.0});
  EXPECT_EQ(j::pgn_of(f), j::kPgnEec1);
  EXPECT_EQ(raw_id(f), 0x0CF00400u);          // J1939-71's EEC1 identifier, priority 3
  EXPECT_EQ(f.data[5], j::kGovernorAddress);  // no override: the engine controls itself
  auto d = j::decode_eec1(f);
  ASSERT_TRUE(d);
  EXPECT_DOUBLE_EQ(d->speed_rpm, 600.375);
  EXPECT_DOUBLE_EQ(d->actual_torque_pct, 80.0);
  const can_frame overridden = j::encode_eec1({600.0, 80.0, j::kRigAddress});
  EXPECT_EQ(overridden.data[5], 0xF9);
  EXPECT_EQ(j::decode_eec1(overridden)->controlling_address, j::kRigAddress);
}

// Priority 3 for control (TSC1, EEC1 as J1939-71; 0xFF50 like TSC1), 6 for the data frames.
TEST(J1939Id, PrioritiesOfEveryFrame) {
  auto priority = [](const can_frame& f) { return j::decode_id(raw_id(f)).priority; };
  EXPECT_EQ(priority(j::encode_tsc1({600.0, 0})), 3);
  EXPECT_EQ(priority(j::encode_eec1({600.0, 0.0})), 3);
  EXPECT_EQ(priority(j::encode_rig_command({0.0, true, 0})), 3);
  EXPECT_EQ(priority(j::encode_gtacp({1e6, 0.0})), 6);
  EXPECT_EQ(priority(j::encode_plant_sample({1e6, 1, 0})), 6);
  EXPECT_EQ(priority(j::encode_lockstep({1})), 6);
  EXPECT_EQ(priority(j::encode_bias_echo({})), 6);
  EXPECT_EQ(raw_id(j::encode_gtacp({1e6, 0.0})), 0x18FE0500u);  // J1939-71's GTACP identifier
  EXPECT_EQ(raw_id(j::encode_rig_command({0.0, true, 0})), 0x0CFF50F9u);
  EXPECT_EQ(raw_id(j::encode_bias_echo({})), 0x18FF5300u);
}

TEST(J1939RigCommand, RoundTripAndQuantisation) {
  for (double bias : {0.0, 1.2345, -2.9996, 3.0, -0.001, -0.512}) {
    const can_frame f = j::encode_rig_command({bias, true, 9});
    auto d = j::decode_rig_command(f, std::uint8_t{8});
    ASSERT_TRUE(d) << d.error().message();
    EXPECT_DOUBLE_EQ(d->bias_pct, drivers::bias_from_raw(drivers::quantise_bias(bias)))
        << "CAN and Modbus must quantise alike";
    EXPECT_NEAR(d->bias_pct, bias, 0.0005 + 1e-12);  // half a bit
    EXPECT_TRUE(d->enable);
    EXPECT_FALSE(d->keep_enable);
    EXPECT_EQ(d->counter, 9);
  }
  // 1.2345 % -> round(1234.5) + 32000 = 33235 = 0x81D3, little-endian.
  const can_frame f = j::encode_rig_command({1.2345, false, 0});
  EXPECT_EQ(f.data[0], 0xD3);
  EXPECT_EQ(f.data[1], 0x81);
  // -0.001 % -> 31999 = 0x7CFF: a value, not J1939's "not available" 0xFFFF.
  const can_frame small = j::encode_rig_command({-0.001, true, 0});
  EXPECT_EQ(small.data[0], 0xFF);
  EXPECT_EQ(small.data[1], 0x7C);
  EXPECT_EQ(j::encode_rig_command({0.0, true, 0}).data[1], 0x7D);  // 32000 = 0x7D00: 0 %
}

// Byte 2: the J1939 2-bit state, reserved bits 1: 0xFC disable, 0xFD enable, 0xFF don't care.
TEST(J1939RigCommand, EnableIsATwoBitStateField) {
  EXPECT_EQ(j::encode_rig_command({0.5, false, 1}).data[2], 0xFC);
  EXPECT_EQ(j::encode_rig_command({0.5, true, 1}).data[2], 0xFD);
  const can_frame keep = j::encode_rig_command({0.5, true, 1, true});
  EXPECT_EQ(keep.data[2], 0xFF);
  auto k = j::decode_rig_command(keep);
  ASSERT_TRUE(k);
  EXPECT_TRUE(k->keep_enable);
  EXPECT_FALSE(k->enable);
  // 10 is J1939's error indicator: the frame is refused.
  can_frame error = j::encode_rig_command({0.5, true, 1});
  error.data[2] = 0xFE;
  error.data[7] = static_cast<std::uint8_t>((1 << 4) | j::checksum4(error.data, 1, raw_id(error)));
  auto e = j::decode_rig_command(error);
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().kind, LinkErrorKind::kProtocol);
  EXPECT_NE(e.error().detail.find("enable state 10"), std::string::npos);
}

// Every bias of +-32 % in 0.001 % steps encodes inside 0x0000..0xFAFF and back to itself.
TEST(J1939Bias, SlotCoversPlusMinus32PercentOutsideReservedRanges) {
  int bad = 0;
  for (int k = -32000; k <= 32000; ++k) {
    const std::uint16_t raw = j::encode_bias(k * 0.001);
    const auto back = j::decode_bias(raw);
    if (raw > 0xFAFF || !back || std::abs(*back - k * 0.001) > 1e-9) ++bad;
  }
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(j::encode_bias(0.0), 32000);
  EXPECT_EQ(j::encode_bias(std::nan("")), 32000);  // NaN is no bias
  EXPECT_EQ(j::encode_bias(1000.0), 0xFAFF);       // clamped to +32.255 %
  EXPECT_EQ(j::encode_bias(-1000.0), 0x0000);      // clamped to -32.000 %
  EXPECT_DOUBLE_EQ(*j::decode_bias(0xFAFF), 32.255);
  EXPECT_DOUBLE_EQ(j::quantise_bias_slot(-40.0), -32.0);
  for (std::uint32_t raw : {0xFB00u, 0xFDFFu, 0xFE00u, 0xFFFFu}) {
    EXPECT_FALSE(j::decode_bias(static_cast<std::uint16_t>(raw))) << raw;
  }
}

TEST(J1939RigCommand, ReservedBiasValuesAreRefused) {
  can_frame f = j::encode_rig_command({0.5, true, 2});
  f.data[0] = 0xFF;  // bias 0xFFFF: "not available"
  f.data[1] = 0xFF;
  f.data[7] = static_cast<std::uint8_t>((2 << 4) | j::checksum4(f.data, 2, raw_id(f)));
  auto r = j::decode_rig_command(f);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kProtocol);
  EXPECT_NE(r.error().detail.find("not available"), std::string::npos) << r.error().detail;
}

TEST(J1939BiasEcho, RoundTripAndLayout) {
  const can_frame f = j::encode_bias_echo({-0.512, 7.5, 0x1234, 0x07, 11});
  EXPECT_EQ(j::pgn_of(f), j::kPgnBiasEcho);
  EXPECT_EQ(f.data[0] | (f.data[1] << 8), 32000 - 512);
  EXPECT_EQ(f.data[2] | (f.data[3] << 8), 32000 + 7500);
  EXPECT_EQ(f.data[4], 0x34);
  EXPECT_EQ(f.data[5], 0x12);
  EXPECT_EQ(f.data[6], 0x07);
  EXPECT_EQ(f.data[7] >> 4, 11);
  auto d = j::decode_bias_echo(f);
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_DOUBLE_EQ(d->applied_pct, -0.512);
  EXPECT_DOUBLE_EQ(d->received_pct, 7.5);
  EXPECT_EQ(d->sample_counter, 0x1234);
  EXPECT_EQ(d->status, 0x07);
  EXPECT_EQ(d->command_counter, 11);
  can_frame bad = f;
  bad.data[0] ^= 0x04;
  EXPECT_EQ(j::decode_bias_echo(bad).error().kind, LinkErrorKind::kChecksum);
}

TEST(J1939RigCommand, ChecksumMatchesDocumentedFormula) {
  const can_frame f = j::encode_rig_command({0.5, true, 7});
  // s = sum(data[0..6]) + counter + id bytes; cs = ((s >> 4) + s) & 0xF
  std::uint32_t s = 7;
  for (int i = 0; i < 7; ++i) s += f.data[i];
  const std::uint32_t id = raw_id(f);
  s += (id & 0xFF) + ((id >> 8) & 0xFF) + ((id >> 16) & 0xFF) + ((id >> 24) & 0xFF);
  EXPECT_EQ(f.data[7] & 0x0F, ((s >> 4) + s) & 0x0F);
  EXPECT_EQ(f.data[7] >> 4, 7);
}

TEST(J1939RigCommand, DetectsCorruptionWrongSenderAndCounterJump) {
  const can_frame good = j::encode_rig_command({0.5, true, 3});
  can_frame bad = good;
  bad.data[0] ^= 0x01;  // one flipped bit in the bias
  auto r = j::decode_rig_command(bad);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kChecksum);
  EXPECT_EQ(r.error().where, "PGN 0xFF50");

  // The identifier is in the checksum, so a frame re-addressed from another sender fails
  // unless its 4-bit checksum collides (expected 1 in 16).
  int detected = 0;
  for (std::uint32_t sa = 0; sa < 256; ++sa) {
    if (sa == j::kRigAddress) continue;
    can_frame other = good;
    other.can_id = (other.can_id & ~0xFFu) | sa;
    detected += j::decode_rig_command(other) ? 0 : 1;
  }
  EXPECT_GE(detected, 255 * 14 / 16);

  auto jump = j::decode_rig_command(good, std::uint8_t{1});  // 1 -> 3 skips one frame
  ASSERT_FALSE(jump);
  EXPECT_EQ(jump.error().kind, LinkErrorKind::kChecksum);
  EXPECT_NE(jump.error().detail.find("expected 2"), std::string::npos);
  EXPECT_TRUE(j::decode_rig_command(j::encode_rig_command({0, true, 0}), std::uint8_t{15}));
}

TEST(J1939PlantSample, RoundTripAndCounterNibble) {
  const can_frame f = j::encode_plant_sample({3.5e6, 0x1234, 0x07});
  auto d = j::decode_plant_sample(f);
  ASSERT_TRUE(d) << d.error().message();
  EXPECT_DOUBLE_EQ(d->power_w, 3.5e6);
  EXPECT_EQ(d->counter, 0x1234);
  EXPECT_EQ(d->status, 0x07);
  EXPECT_EQ(f.data[4], 0x34);
  EXPECT_EQ(f.data[5], 0x12);
  EXPECT_EQ(f.data[7] >> 4, 0x4);

  can_frame bad = f;
  bad.data[4] = 0x35;  // counter changed without resealing
  EXPECT_EQ(j::decode_plant_sample(bad).error().kind, LinkErrorKind::kChecksum);
}

TEST(J1939Lockstep, RoundTrip) {
  const can_frame f = j::encode_lockstep({500});
  EXPECT_EQ(j::pgn_of(f), j::kPgnLockstep);
  EXPECT_EQ(j::decode_lockstep(f)->ticks, 500);
}

TEST(J1939Decode, RejectsLengthPgnAndFrameType) {
  can_frame f = j::encode_plant_sample({1e6, 1, 0});
  can_frame shorter = f;
  shorter.can_dlc = 6;
  auto r = j::decode_plant_sample(shorter);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kProtocol);
  EXPECT_NE(r.error().detail.find("expected 8 data bytes, got 6"), std::string::npos);

  auto wrong = j::decode_eec1(f);
  ASSERT_FALSE(wrong);
  EXPECT_EQ(wrong.error().kind, LinkErrorKind::kProtocol);
  EXPECT_NE(wrong.error().detail.find("PGN 0xFF51"), std::string::npos);

  can_frame standard = f;
  standard.can_id = 0x123;
  EXPECT_EQ(j::decode_plant_sample(standard).error().kind, LinkErrorKind::kProtocol);
}

// A change of one data bit moves s by +-2^k: for k < 4 the low nibble of ((s >> 4) + s)
// changes by 2^k or 2^k +- 1, for k >= 4 by 2^(k-4); never by 0 mod 16. So every single-bit
// error in bytes 0-6 must be caught; checked exhaustively on seeded random frames.
TEST(J1939Checksum, EverySingleBitErrorInTheDataIsDetected) {
  constexpr unsigned kSeed = 20261121;
  std::printf("seed %u\n", kSeed);
  std::srand(kSeed);
  int missed = 0;
  int flips = 0;
  for (int n = 0; n < 500; ++n) {
    const double bias = (std::rand() % 60001 - 30000) * 0.001;
    const auto counter = static_cast<std::uint8_t>(std::rand() % 16);
    const can_frame good = j::encode_rig_command({bias, (std::rand() & 1) != 0, counter});
    for (int byte = 0; byte < 7; ++byte) {
      for (int bit = 0; bit < 8; ++bit) {
        can_frame bad = good;
        bad.data[byte] ^= static_cast<std::uint8_t>(1u << bit);
        ++flips;
        auto r = j::decode_rig_command(bad);  // the checksum is checked before the values
        missed += (r || r.error().kind != LinkErrorKind::kChecksum) ? 1 : 0;
      }
    }
  }
  EXPECT_EQ(missed, 0) << "of " << flips << " single-bit errors";
}
