// Independent Modbus client implementations against plantsim: Debian's mbpoll (TCP and RTU)
// and pymodbus 3.0 (Debian's python3-pymodbus). Skipped with the reason when a tool is absent.
#include <cstdio>
#include <filesystem>
#include <regex>
#include <sstream>

#include "tests/integration/serve/serve_fixture.hpp"

namespace plantsim::testing {
namespace {

namespace map = drivers::modbus_map;

struct CommandResult {
  int exit_code = -1;
  std::string output;
};

CommandResult run_command(const std::string& command) {
  CommandResult r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) r.output += buf;
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// mbpoll prints one "[address]: value" line per register.
std::map<int, long> parse_mbpoll(const std::string& out) {
  std::map<int, long> values;
  const std::regex line(R"(\[(\d+)\]:\s+(-?\d+))");
  for (std::sregex_iterator it(out.begin(), out.end(), line), end; it != end; ++it) {
    values[std::stoi((*it)[1])] = std::stol((*it)[2]);
  }
  return values;
}

std::string mbpoll_tcp(int port) {
  return "timeout 10 mbpoll -m tcp -p " + std::to_string(port) + " -a 1 -0 -1 -o 2";
}

TEST(ExternalClients, MbpollWritesBiasAndReadsInputRegisters) {
  if (!std::filesystem::exists("/usr/bin/mbpoll")) GTEST_SKIP() << "mbpoll not installed";
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  ASSERT_GT(s.modbus_port, 0);
  const std::string base = mbpoll_tcp(s.modbus_port);
  auto w = run_command(base + " -t 4 -r 0 127.0.0.1 1750 1 1");
  ASSERT_EQ(w.exit_code, 0) << w.output;
  auto a = run_command(base + " -t 4 -r 100 127.0.0.1 25");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  auto r = run_command(base + " -t 3 -r 0 -c 10 127.0.0.1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto values = parse_mbpoll(r.output);
  ASSERT_EQ(values.size(), 10u) << r.output;
  EXPECT_EQ(values.at(map::kInBiasEcho), 1750);
  EXPECT_EQ(values.at(map::kInCounter), 25);
  EXPECT_EQ(values.at(map::kInTimeLo), 25);   // plant time 25 ms
  EXPECT_EQ(values.at(map::kInFreq), 50000);  // 50.000 Hz
  EXPECT_EQ(values.at(map::kInSpeed), 6000);  // 600.0 rpm
  // An illegal address is reported by mbpoll as the server's exception.
  auto bad = run_command(base + " -t 3 -r 10 -c 1 127.0.0.1");
  EXPECT_NE(bad.output.find("Illegal data address"), std::string::npos) << bad.output;
}

TEST(ExternalClients, PymodbusWritesBiasAndReadsPower) {
  if (!std::filesystem::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3";
  auto probe = run_command("/usr/bin/python3 -c 'import pymodbus'");
  if (probe.exit_code != 0) GTEST_SKIP() << "pymodbus not installed: " << probe.output;
  auto s = start_served(linear_program(), {"--modbus", "tcp://127.0.0.1:0", "--clock", "lockstep"});
  ASSERT_GT(s.modbus_port, 0);
  // Debian's pymodbus 3.0.0rc1 imports serial_asyncio (not packaged) even for TCP: stub it.
  std::ostringstream py;
  py << "import sys, types\n"
     << "sys.modules.setdefault('serial_asyncio', types.SimpleNamespace("
        "create_serial_connection=None))\n"
     << "from pymodbus.client import ModbusTcpClient\n"
     << "c = ModbusTcpClient('127.0.0.1', port=" << s.modbus_port << ")\n"
     << "assert c.connect()\n"
     << "for k in range(20):\n"
     << "    c.write_registers(0, [(-2000) & 0xFFFF, k + 1, 1], slave=1)\n"
     << "    c.write_register(100, 50, slave=1)\n"
     << "r = c.read_input_registers(0, 10, slave=1)\n"
     << "print(' '.join(str(v) for v in r.registers))\n"
     << "e = c.read_input_registers(9, 2, slave=1)\n"
     << "print('exception', e.isError(), getattr(e, 'exception_code', None))\n"
     << "c.close()\n";
  const auto script = std::filesystem::temp_directory_path() /
                      ("plantsim_pymodbus_" + std::to_string(getpid()) + ".py");
  {
    FILE* f = std::fopen(script.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs(py.str().c_str(), f);
    std::fclose(f);
  }
  const auto out = run_command("timeout 30 /usr/bin/python3 " + script.string());
  std::filesystem::remove(script);
  ASSERT_EQ(out.exit_code, 0) << out.output;
  std::istringstream lines(out.output);
  std::vector<long> regs(10);
  for (auto& v : regs) lines >> v;
  ASSERT_TRUE(lines) << out.output;
  EXPECT_EQ(static_cast<std::int16_t>(regs[map::kInBiasEcho]), -2000);
  EXPECT_EQ(regs[map::kInCounter], 1000);
  // Linear plant, gain 1 %/%, 2 Hz, zeta 0.1: after 1 s of -2 % the power is well below the
  // 3.5 MW operating point (steady state -92 kW, 4.6 MW rated).
  const long power_w = (regs[0] << 16) | regs[1];
  EXPECT_LT(power_w, 3.5e6 - 40e3);
  EXPECT_GT(power_w, 3.5e6 - 200e3);
  EXPECT_NE(out.output.find("exception True 2"), std::string::npos) << out.output;
}

}  // namespace
}  // namespace plantsim::testing
