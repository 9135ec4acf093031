// plantsim's Modbus TCP server against a real libmodbus client over 127.0.0.1: the register
// map, lockstep, heartbeat loss, and misbehaving clients.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <thread>

#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

namespace map = drivers::modbus_map;
using Clock = std::chrono::steady_clock;

int raw_connect(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    close(fd);
    return -1;
  }
  timeval tv{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  return fd;
}

TEST(ModbusTcp, LockstepAdvancesExactlyTheTicksWrittenBeforeAnswering) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  const auto r0 = read_inputs(ctx.get());
  EXPECT_EQ(r0[map::kInCounter], 0);
  EXPECT_EQ(time_ms_of(r0), 0u);
  std::this_thread::sleep_for(50ms);  // lockstep: wall time must not move the plant
  EXPECT_EQ(read_inputs(ctx.get())[map::kInCounter], 0);
  advance(ctx.get(), 37);
  const auto r1 = read_inputs(ctx.get());
  EXPECT_EQ(r1[map::kInCounter], 37);
  EXPECT_EQ(time_ms_of(r1), 37u);
  // The answer to a read of holding 100 is the last N written.
  std::uint16_t n = 0;
  ASSERT_EQ(modbus_read_registers(ctx.get(), map::kHoldLockstepTicks, 1, &n), 1);
  EXPECT_EQ(n, 37);
}

TEST(ModbusTcp, BiasAppliedOnlyWhenEnabledAndEchoedWithStatus) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  write_command(ctx.get(), -1234, 1, /*enable=*/false);
  advance(ctx.get(), 1);
  auto r = read_inputs(ctx.get());
  EXPECT_EQ(bias_echo_of(r), 0);
  EXPECT_EQ(r[map::kInStatus] & drivers::kBiasActive, 0);
  EXPECT_EQ(r[map::kInStatus] & drivers::kHeartbeatLost, 0);
  write_command(ctx.get(), -1234, 2, /*enable=*/true);
  advance(ctx.get(), 1);
  r = read_inputs(ctx.get());
  EXPECT_EQ(bias_echo_of(r), -1234);
  EXPECT_NE(r[map::kInStatus] & drivers::kBiasActive, 0);
  EXPECT_NE(r[map::kInStatus] & drivers::kRunning, 0);
  // Holding registers read back what was written.
  std::uint16_t h[3] = {};
  ASSERT_EQ(modbus_read_registers(ctx.get(), 0, 3, h), 3);
  EXPECT_EQ(static_cast<std::int16_t>(h[0]), -1234);
  EXPECT_EQ(h[1], 2);
  EXPECT_EQ(h[2], 1);
}

// In lockstep the heartbeat rule runs on plant time: the bias survives 500 ticks of 1 ms
// without a heartbeat change and is gone at the 501st (500 ms + 1 tick).
TEST(ModbusTcp, LockstepHeartbeatLossAfter500msOfPlantTime) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  write_command(ctx.get(), 2500, 1);
  advance(ctx.get(), 500);
  auto r = read_inputs(ctx.get());
  EXPECT_EQ(bias_echo_of(r), 2500);
  EXPECT_EQ(r[map::kInStatus] & drivers::kHeartbeatLost, 0);
  advance(ctx.get(), 1);
  r = read_inputs(ctx.get());
  EXPECT_EQ(bias_echo_of(r), 0);
  EXPECT_NE(r[map::kInStatus] & drivers::kHeartbeatLost, 0);
  EXPECT_EQ(r[map::kInStatus] & drivers::kBiasActive, 0);
  // Writing the same heartbeat value again is not a heartbeat.
  write_command(ctx.get(), 2500, 1);
  advance(ctx.get(), 1);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 0);
  // A changed heartbeat re-applies the freshly written bias.
  write_command(ctx.get(), 2500, 2);
  advance(ctx.get(), 1);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 2500);
}

// Realtime: the rule is checked on the plant clock the answers carry, so a test process that
// is scheduled late on a busy machine cannot blur it. t_before/t_after are the plant times
// read just before and after the last heartbeat write (the server saw it in between). Every
// answer stamped at or before t_before + 500 ms must still carry the bias; every answer stamped
// at or after t_after + 500 ms + 1 tick must carry zero. Separately, plant time must follow
// the monotonic clock (it may lag by scheduling delays of this process, allowed 50 ms, and
// never run ahead), which makes the plant-time bound a wall-time bound.
TEST(ModbusTcp, RealtimeHeartbeatLossWithin500msPlusOneTick) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  const auto wall0 = Clock::now();
  const auto plant0_ms = time_ms_of(read_inputs(ctx.get()));
  for (std::uint16_t hb = 1; hb <= 10; ++hb) {
    write_command(ctx.get(), 1500, hb);
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 1500);
  const auto t_before = time_ms_of(read_inputs(ctx.get()));
  write_command(ctx.get(), 1500, 11);
  const auto t_after = time_ms_of(read_inputs(ctx.get()));
  int alive_seen = 0;
  int dropped_seen = 0;
  std::array<std::uint16_t, 10> r{};
  while (dropped_seen < 20 && Clock::now() - wall0 < 5s) {
    r = read_inputs(ctx.get());
    const auto t = time_ms_of(r);
    if (t <= t_before + 500) {
      EXPECT_EQ(bias_echo_of(r), 1500) << "dropped early at plant time " << t;
      ++alive_seen;
    }
    if (t >= t_after + 501) {
      EXPECT_EQ(bias_echo_of(r), 0) << "still applied at plant time " << t;
      EXPECT_NE(r[map::kInStatus] & drivers::kHeartbeatLost, 0);
      ++dropped_seen;
    }
    std::this_thread::sleep_for(1ms);
  }
  EXPECT_GT(alive_seen, 0);
  EXPECT_EQ(dropped_seen, 20);
  const auto wall1 = Clock::now();
  const auto plant1_ms = time_ms_of(read_inputs(ctx.get()));
  const double wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - wall0).count();
  const double plant_ms = static_cast<double>(plant1_ms - plant0_ms);
  std::printf("heartbeat write seen between plant %u and %u ms; plant %.0f ms over wall %.1f ms\n",
              t_before, t_after, plant_ms,
              std::chrono::duration<double, std::milli>(wall1 - wall0).count());
  EXPECT_LE(plant_ms, wall_ms + 1.0);
  EXPECT_GE(plant_ms, wall_ms - 50.0);
}

TEST(ModbusTcp, IllegalAddressesAndFunctionsAnsweredWithExceptions) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  std::uint16_t regs[20] = {};
  EXPECT_EQ(modbus_read_input_registers(ctx.get(), 5, 6, regs), -1);  // 5..10: 10 is past the end
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_registers(ctx.get(), 101, 1, regs), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_register(ctx.get(), 200, 1), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_registers(ctx.get(), 99, 3, regs), -1);  // 99..101
  EXPECT_EQ(errno, EMBXILADD);
  std::uint8_t bits[8] = {};
  EXPECT_EQ(modbus_read_bits(ctx.get(), 0, 1, bits), -1);  // no coils: function not served
  EXPECT_EQ(errno, EMBXILFUN);
  // An unknown function code (0x41) -> exception 01, illegal function.
  const std::uint8_t raw[] = {1, 0x41, 0, 0, 0, 1};
  ASSERT_GT(modbus_send_raw_request(ctx.get(), raw, sizeof raw), 0);
  std::uint8_t rsp[MODBUS_TCP_MAX_ADU_LENGTH];
  EXPECT_EQ(modbus_receive_confirmation(ctx.get(), rsp), 9);
  EXPECT_EQ(rsp[7], 0x41 | 0x80);
  EXPECT_EQ(rsp[8], MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  // An illegal write changed nothing and the connection still works.
  EXPECT_EQ(modbus_read_registers(ctx.get(), 0, 3, regs), 3);
  EXPECT_EQ(regs[0], 0);
}

// Only 03/04/06/16 are served. libmodbus alone would write holding registers through 0x16 and
// 0x17 and leave 07 unanswered (the client timing out); every other code is exception 01.
TEST(ModbusTcp, UndocumentedFunctionsAreRefusedWithIllegalFunction) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  write_command(ctx.get(), 1000, 1);
  EXPECT_EQ(modbus_mask_write_register(ctx.get(), map::kHoldBias, 0x0000, 0x0BB8), -1);
  EXPECT_EQ(errno, EMBXILFUN) << modbus_strerror(errno);
  const std::uint16_t bias[1] = {2500};
  std::uint16_t back[1] = {};
  EXPECT_EQ(modbus_write_and_read_registers(ctx.get(), map::kHoldBias, 1, bias, 0, 1, back), -1);
  EXPECT_EQ(errno, EMBXILFUN) << modbus_strerror(errno);
  for (const std::uint8_t function : {0x07, 0x11, 0x2B, 0x01, 0x05}) {
    const std::uint8_t raw[] = {1, function, 0, 0, 0, 1};
    ASSERT_GT(modbus_send_raw_request(ctx.get(), raw, function == 0x07 ? 2 : sizeof raw), 0);
    std::uint8_t rsp[MODBUS_TCP_MAX_ADU_LENGTH];
    ASSERT_EQ(modbus_receive_confirmation(ctx.get(), rsp), 9)
        << "function " << int{function} << ": " << modbus_strerror(errno);
    EXPECT_EQ(rsp[7], function | 0x80);
    EXPECT_EQ(rsp[8], MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  }
  // Nothing of the refused writes reached the governor.
  std::uint16_t h = 0;
  ASSERT_EQ(modbus_read_registers(ctx.get(), map::kHoldBias, 1, &h), 1);
  EXPECT_EQ(h, 1000);
  advance(ctx.get(), 1);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 1000);
}

// The governor clamps the external bias (gov.ext_bias_limit_pct, 5 % by default): input 5
// echoes what it applies, so the rig sees the clamp as an echo departing from its command.
TEST(ModbusTcp, GovernorClampsTheAppliedBias) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  write_command(ctx.get(), 7500, 1);
  advance(ctx.get(), 1);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 5000);
  write_command(ctx.get(), -12000, 2);
  advance(ctx.get(), 1);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), -5000);
  write_command(ctx.get(), 4999, 3);
  advance(ctx.get(), 1);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 4999);
}

// The clamp is a plant parameter: --list-params shows it and --fault changes it.
TEST(ModbusTcp, RealPlantClampIsAParameter) {
  if (!real_program_exists()) GTEST_SKIP() << real_program() << " has not been built";
  const auto list = run_to_end({"--list-params"}, real_program());
  EXPECT_NE(list.out.find("ext_bias_limit_pct = 5 "), std::string::npos) << list.out;
  auto s = start_served(real_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep",
                                         "--fault", "gov.ext_bias_limit_pct=2@t=0.005"});
  auto ctx = connect_tcp(s.modbus_port);
  ASSERT_TRUE(ctx);
  write_command(ctx.get(), 3000, 1);
  advance(ctx.get(), 2);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 3000);
  write_command(ctx.get(), 3000, 2);
  advance(ctx.get(), 10);
  EXPECT_EQ(bias_echo_of(read_inputs(ctx.get())), 2000);
}

// Garbage on one connection closes that connection only; a half frame from a stalled client
// does not delay the others; new connections are still accepted.
TEST(ModbusTcp, GarbageAndStalledClientsDoNotStopTheServer) {
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  auto good = connect_tcp(s.modbus_port);
  ASSERT_TRUE(good);
  const int garbage = raw_connect(s.modbus_port);
  const int stalled = raw_connect(s.modbus_port);
  ASSERT_GE(garbage, 0);
  ASSERT_GE(stalled, 0);
  const char junk[] = "GET / HTTP/1.1\r\nHost: plantsim\r\n\r\n";
  ASSERT_GT(send(garbage, junk, sizeof junk - 1, 0), 0);
  char buf[64];
  EXPECT_EQ(recv(garbage, buf, sizeof buf, 0), 0) << "a non-Modbus stream should be closed";
  const std::uint8_t half[] = {0x00, 0x01, 0x00};  // 3 of a 12-byte request, never finished
  ASSERT_EQ(send(stalled, half, sizeof half, 0), 3);
  const auto t0 = Clock::now();
  advance(good.get(), 5);
  EXPECT_EQ(read_inputs(good.get())[map::kInCounter], 5);
  EXPECT_LT(Clock::now() - t0, 200ms);
  auto late = connect_tcp(s.modbus_port);
  ASSERT_TRUE(late);
  EXPECT_EQ(read_inputs(late.get())[map::kInCounter], 5);
  close(garbage);
  close(stalled);
}

TEST(ModbusTcp, LockstepIsDeterministicForASeed) {
  const auto a = lockstep_recording(linear_program(), "7");
  const auto b = lockstep_recording(linear_program(), "7");
  const auto c = lockstep_recording(linear_program(), "8");
  ASSERT_EQ(a.size(), 3000u);
  EXPECT_EQ(a, b) << "seed 7 twice";
  EXPECT_NE(a, c) << "seeds 7 and 8 should differ (the plant has measurement noise)";
  // Each exchange advanced exactly 10 ticks.
  for (std::size_t k = 0; k < 300; ++k) EXPECT_EQ(a[10 * k + map::kInCounter], 10 * (k + 1));
}

}  // namespace
}  // namespace plantsim::testing
