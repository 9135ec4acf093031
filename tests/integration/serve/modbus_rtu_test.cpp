// plantsim as a Modbus RTU slave on a pseudo-terminal pair made by
//   socat -d -d pty,raw,echo=0 pty,raw,echo=0
// (plantsim on one end, libmodbus and mbpoll as masters on the other).
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <regex>
#include <thread>

#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

namespace map = drivers::modbus_map;

struct PtyPair {
  std::unique_ptr<ChildProcess> socat;
  std::string a, b;
};

PtyPair open_pty_pair() {
  PtyPair p;
  p.socat = std::make_unique<ChildProcess>(
      std::vector<std::string>{"/usr/bin/socat", "-d", "-d", "pty,raw,echo=0", "pty,raw,echo=0"});
  const std::regex pty(R"(PTY is (\S+))");
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    const std::string err = p.socat->stderr_text(100ms);
    std::vector<std::string> found;
    for (std::sregex_iterator it(err.begin(), err.end(), pty), end; it != end; ++it) {
      found.push_back((*it)[1]);
    }
    if (found.size() >= 2 && err.find("starting data transfer loop") != std::string::npos) {
      p.a = found[0];
      p.b = found[1];
      break;
    }
  }
  return p;
}

// Modbus RTU CRC-16 (polynomial 0xA001 reflected, initial 0xFFFF), appended low byte first.
std::vector<std::uint8_t> with_crc(std::vector<std::uint8_t> frame) {
  std::uint16_t crc = 0xFFFF;
  for (const auto byte : frame) {
    crc ^= byte;
    for (int i = 0; i < 8; ++i) crc = (crc & 1) ? (crc >> 1) ^ 0xA001 : crc >> 1;
  }
  frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  frame.push_back(static_cast<std::uint8_t>(crc >> 8));
  return frame;
}

struct RtuDeleter {
  void operator()(modbus_t* ctx) const {
    modbus_close(ctx);
    modbus_free(ctx);
  }
};

TEST(ModbusRtu, ServesThroughAPtyPairAndSurvivesNoise) {
  if (!std::filesystem::exists("/usr/bin/socat")) GTEST_SKIP() << "socat not installed";
  auto pty = open_pty_pair();
  ASSERT_FALSE(pty.a.empty()) << "socat did not report two ptys: " << pty.socat->stderr_text();
  auto s = start_served(linear_program(),
                        {"--modbus", "rtu:" + pty.a + "?baud=19200", "--clock", "lockstep"});
  ASSERT_TRUE(s.process);
  std::unique_ptr<modbus_t, RtuDeleter> ctx(modbus_new_rtu(pty.b.c_str(), 19200, 'N', 8, 1));
  ASSERT_TRUE(ctx);
  ASSERT_EQ(modbus_connect(ctx.get()), 0) << modbus_strerror(errno);
  modbus_set_response_timeout(ctx.get(), 1, 0);
  modbus_set_slave(ctx.get(), 1);
  write_command(ctx.get(), 3210, 1);
  advance(ctx.get(), 12);
  auto r = read_inputs(ctx.get());
  EXPECT_EQ(bias_echo_of(r), 3210);
  EXPECT_EQ(r[map::kInCounter], 12);

  // Line noise (no valid frame) is dropped by the slave; the next request is answered.
  const int fd = modbus_get_socket(ctx.get());
  const std::uint8_t noise[] = {0x55, 0xAA, 0x13, 0x37, 0x00, 0xFF, 0x42};
  ASSERT_EQ(write(fd, noise, sizeof noise), static_cast<ssize_t>(sizeof noise));
  std::this_thread::sleep_for(300ms);  // past the slave's 100 ms byte timeout
  modbus_flush(ctx.get());
  EXPECT_EQ(read_inputs(ctx.get())[map::kInCounter], 12);

  std::uint16_t regs[2];
  EXPECT_EQ(modbus_read_input_registers(ctx.get(), 9, 2, regs), -1);
  EXPECT_EQ(errno, EMBXILADD);
  // Function 07 is not served: exception 01 rather than silence (the master's timeout).
  const std::uint8_t fc07[] = {1, 0x07};
  ASSERT_GT(modbus_send_raw_request(ctx.get(), fc07, sizeof fc07), 0);
  std::uint8_t rsp[MODBUS_RTU_MAX_ADU_LENGTH];
  ASSERT_EQ(modbus_receive_confirmation(ctx.get(), rsp), 5) << modbus_strerror(errno);
  EXPECT_EQ(rsp[1], 0x87);
  EXPECT_EQ(rsp[2], MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  // A request for another unit on the bus gets no answer from us. As on a real RS-485 bus,
  // the other unit answers it; the slave reads and discards that answer, then serves ours.
  const std::uint8_t other_request[] = {7, 0x04, 0x00, 0x00, 0x00, 0x01};
  ASSERT_GT(modbus_send_raw_request(ctx.get(), other_request, sizeof other_request), 0);
  std::this_thread::sleep_for(50ms);
  const auto other_answer = with_crc({7, 0x04, 0x02, 0x12, 0x34});
  ASSERT_EQ(write(fd, other_answer.data(), other_answer.size()),
            static_cast<ssize_t>(other_answer.size()));
  std::this_thread::sleep_for(50ms);
  modbus_flush(ctx.get());  // our own end also saw nothing but those two frames
  EXPECT_EQ(read_inputs(ctx.get())[map::kInCounter], 12);
  ctx.reset();

  // Debian's mbpoll as the RTU master.
  if (std::filesystem::exists("/usr/bin/mbpoll")) {
    const std::string cmd =
        "timeout 10 mbpoll -m rtu -b 19200 -P none -a 1 -0 -1 -o 2 -t 3 -r 9 "
        "-c 1 " +
        pty.b + " 2>&1";
    FILE* pipe = popen(cmd.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string out;
    char buf[512];
    while (std::fgets(buf, sizeof buf, pipe) != nullptr) out += buf;
    pclose(pipe);
    EXPECT_NE(out.find("[9]: \t12"), std::string::npos) << out;
  }
}

}  // namespace
}  // namespace plantsim::testing
