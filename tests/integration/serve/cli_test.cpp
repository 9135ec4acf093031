// The plantsim command line (DESIGN.md section 4): --help, bad input exits 2 with one line
// naming what was wrong, resources in use, clean exits on SIGINT/SIGTERM and --duration.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>

#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

void expect_usage_error(const std::vector<std::string>& args, const std::string& names,
                        const std::string& program = linear_program()) {
  const auto o = run_to_end(args, program);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find(names), std::string::npos)
      << "message should name '" << names << "': " << o.err;
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "one line: " << o.err;
  EXPECT_EQ(o.out.find("ready"), std::string::npos) << "nothing may start: " << o.out;
}

TEST(PlantsimCli, RealPlantBadConfigExitsTwo) {
  if (!real_program_exists()) GTEST_SKIP() << real_program() << " has not been built";
  const auto dir = std::filesystem::temp_directory_path();
  const auto write = [&](const std::string& name, const std::string& text) {
    const auto path = dir / (name + std::to_string(getpid()) + ".toml");
    FILE* f = std::fopen(path.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
    return path.string();
  };
  const auto unknown = write("unknown", "[gov]\nno_such_key = 1\n");
  const auto range = write("range", "[gov]\nr_pu = 7\n");
  const auto broken = write("broken", "[gov\nr_pu = \n");
  const std::string real = real_program();
  expect_usage_error({"--preset", "atlantis"}, "atlantis", real);
  expect_usage_error({"--config", unknown}, "no_such_key", real);
  expect_usage_error({"--config", range}, "r_pu", real);
  expect_usage_error({"--config", broken}, broken, real);
  expect_usage_error({"--config", "/nonexistent/plant.toml"}, "/nonexistent/plant.toml", real);
  expect_usage_error({"--fault", "gov.no_such_key=1@t=2"}, "no_such_key", real);
  expect_usage_error({"--fault", "gov.r_pu=abc"}, "gov.r_pu=abc", real);
  for (const auto& f : {unknown, range, broken}) std::filesystem::remove(f);
}

TEST(PlantsimCli, RealPlantLineariseAndListParams) {
  if (!real_program_exists()) GTEST_SKIP() << real_program() << " has not been built";
  const auto file = std::filesystem::temp_directory_path() /
                    ("plantsim_tf_" + std::to_string(getpid()) + ".json");
  const auto o = run_to_end({"--linearise", file.string()}, real_program());
  EXPECT_EQ(o.exit_code, 0) << o.err;
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"type\": \"tf\""), std::string::npos) << text;
  std::filesystem::remove(file);
  const auto list = run_to_end({"--list-params"}, real_program());
  EXPECT_EQ(list.exit_code, 0) << list.err;
  EXPECT_NE(list.out.find("r_pu"), std::string::npos);
}

TEST(PlantsimCli, HelpExitsZero) {
  const auto o = run_to_end({"--help"});
  EXPECT_EQ(o.exit_code, 0);
  for (const char* opt :
       {"--preset", "--config", "--modbus", "--can", "--clock", "--tick", "--fault", "--seed",
        "--linearise", "--duration", "--readout", "--can-rig-address", "--can-sample-period"}) {
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
  expect_usage_error({"--can", "udp://127.0.0.1:0", "--can-rig-address", "0x1F9"},
                     "--can-rig-address");
  expect_usage_error({"--can", "udp://127.0.0.1:0", "--can-rig-address", "F9"},
                     "--can-rig-address");
  expect_usage_error({"--can", "udp://127.0.0.1:0", "--can-sample-period", "often"},
                     "--can-sample-period");
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
