// The plantsim command line (DESIGN.md section 4): --help, bad input exits 2 with one line
// naming what was wrong, resources in use, clean exits on SIGINT/SIGTERM and --duration.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

struct Outcome {
  int exit_code = -1;
  std::string out;
  std::string err;
};

Outcome run_to_end(std::vector<std::string> args, const std::string& program = linear_program()) {
  args.insert(args.begin(), program);
  ChildProcess p(args);
  Outcome o;
  const auto code = p.wait(10s);
  EXPECT_TRUE(code) << "did not exit";
  o.exit_code = code.value_or(-1);
  while (auto line = p.read_line(10ms)) o.out += *line + "\n";
  o.err = p.stderr_text(100ms);
  return o;
}

void expect_usage_error(const std::vector<std::string>& args, const std::string& names) {
  const auto o = run_to_end(args);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find(names), std::string::npos)
      << "message should name '" << names << "': " << o.err;
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "one line: " << o.err;
  EXPECT_EQ(o.out.find("ready"), std::string::npos) << "nothing may start: " << o.out;
}

TEST(PlantsimCli, HelpExitsZero) {
  const auto o = run_to_end({"--help"});
  EXPECT_EQ(o.exit_code, 0);
  for (const char* opt : {"--preset", "--config", "--modbus", "--can", "--clock", "--tick",
                          "--fault", "--seed", "--linearise", "--duration", "--readout"}) {
    EXPECT_NE(o.out.find(opt), std::string::npos) << opt;
  }
}

TEST(PlantsimCli, BadInputExitsTwoWithOneLineNamingIt) {
  expect_usage_error({"--modbus", "tcp://127.0.0.1:0", "--preset", "nosuchset"}, "nosuchset");
  expect_usage_error({"--modbus", "tcp://127.0.0.1:99999"}, "port");
  expect_usage_error({"--modbus", "udp://127.0.0.1:0"}, "--modbus");
  expect_usage_error({"--can", "tcp://127.0.0.1:0"}, "--can");
  expect_usage_error({"--clock", "sometimes"}, "--clock");
  expect_usage_error({"--tick", "1 fortnight"}, "--tick");
  expect_usage_error({"--tick", "10us"}, "--tick");
  expect_usage_error({"--duration", "-1"}, "--duration");
  expect_usage_error({"--seed", "minus-one"}, "--seed");
  expect_usage_error({"--no-such-option"}, "--no-such-option");
  expect_usage_error({"--modbus", "rtu:/dev/plantsim-no-such-tty?baud=19200"},
                     "/dev/plantsim-no-such-tty");
  expect_usage_error({"--modbus", "rtu:/dev/null?baud=fast"}, "baud");
}

TEST(PlantsimCli, PortInUseExitsTwoAndNamesThePort) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ASSERT_EQ(listen(fd, 1), 0);
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  const std::string port = std::to_string(ntohs(addr.sin_port));
  expect_usage_error({"--modbus", "tcp://127.0.0.1:" + port}, port);
  // The Modbus port is free but the CAN one is not: nothing starts, not even Modbus.
  const int udp = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in uaddr{};
  uaddr.sin_family = AF_INET;
  uaddr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(udp, reinterpret_cast<sockaddr*>(&uaddr), sizeof uaddr), 0);
  len = sizeof uaddr;
  getsockname(udp, reinterpret_cast<sockaddr*>(&uaddr), &len);
  const std::string uport = std::to_string(ntohs(uaddr.sin_port));
  expect_usage_error({"--modbus", "tcp://127.0.0.1:0", "--can", "udp://127.0.0.1:" + uport}, uport);
  close(udp);
  close(fd);
}

TEST(PlantsimCli, SocketcanUnavailableIsAConfigError) {
  const auto o = run_to_end({"--can", "socketcan:plantsimcan9"});
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("plantsimcan9"), std::string::npos) << o.err;
}

TEST(PlantsimCli, SigtermAndSigintExitZero) {
  for (const int sig : {SIGTERM, SIGINT}) {
    auto s =
        start_served(linear_program(),
                     {"--modbus", "tcp://127.0.0.1:0", "--can", "udp://127.0.0.1:0"}, true, true);
    ASSERT_GT(s.modbus_port, 0);
    auto ctx = connect_tcp(s.modbus_port);  // a connected client must not delay the exit
    ASSERT_TRUE(ctx);
    s.process->signal(sig);
    EXPECT_EQ(s.process->wait(5s), std::optional<int>(0)) << s.process->stderr_text();
  }
}

TEST(PlantsimCli, DurationStopsAtPlantTimeAndReadoutPrints) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto o = run_to_end({"--modbus", "tcp://127.0.0.1:0", "--duration", "1.2", "--readout"});
  const auto wall = std::chrono::steady_clock::now() - t0;
  EXPECT_EQ(o.exit_code, 0) << o.err;
  EXPECT_GE(wall, 1200ms);  // realtime: plant time follows wall time
  EXPECT_NE(o.out.find("P="), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("bias="), std::string::npos) << o.out;
}

}  // namespace
}  // namespace plantsim::testing
