// The Modbus RTU link over a pseudo-terminal pair made by socat, against a real libmodbus RTU
// server on the other end (skipped when socat is not installed).
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "drivers/open_link.hpp"
#include "modbus_test_server.hpp"

extern char** environ;

using drivers::LinkErrorKind;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

// socat pty,raw,echo=0,link=<dir>/rig pty,raw,echo=0,link=<dir>/plant
class PtyPair {
 public:
  PtyPair() {
    char tmpl[] = "/tmp/rig-rtu-XXXXXX";
    if (::mkdtemp(tmpl)) dir_ = tmpl;
    const std::string a = "pty,raw,echo=0,link=" + rig();
    const std::string b = "pty,raw,echo=0,link=" + plant();
    char* argv[] = {const_cast<char*>("socat"), const_cast<char*>(a.c_str()),
                    const_cast<char*>(b.c_str()), nullptr};
    if (dir_.empty() || ::posix_spawnp(&pid_, "socat", nullptr, nullptr, argv, environ) != 0) {
      pid_ = -1;
      return;
    }
    for (int i = 0; i < 200 && !(fs::exists(rig()) && fs::exists(plant())); ++i) {
      std::this_thread::sleep_for(10ms);
    }
  }
  ~PtyPair() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, nullptr, 0);
    }
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  bool ok() const { return pid_ > 0 && fs::exists(rig()) && fs::exists(plant()); }
  std::string rig() const { return dir_ + "/rig"; }
  std::string plant() const { return dir_ + "/plant"; }

 private:
  std::string dir_;
  pid_t pid_ = -1;
};

drivers::LinkOptions rtu_options() {
  drivers::LinkOptions o;
  o.lockstep = true;
  o.response_timeout = 300ms;
  return o;
}

}  // namespace

TEST(ModbusRtu, LockstepCycleOverPtyPair) {
  PtyPair pty;
  if (!pty.ok()) GTEST_SKIP() << "socat could not make a pty pair; RTU test skipped";
  drivers::testing::ModbusTestServer server(pty.plant(), 38400);
  auto link = drivers::open_link("modbus+rtu:" + pty.rig() + "?baud=38400&unit=1", rtu_options());
  ASSERT_TRUE(link) << link.error().message();
  auto& l = *link.value();
  ASSERT_TRUE(l.configure());
  ASSERT_TRUE(l.activate());
  ASSERT_TRUE(l.write(-0.75));
  ASSERT_TRUE(l.advance(2));
  auto s = l.read();
  ASSERT_TRUE(s) << s.error().message();
  EXPECT_EQ(s->counter, 2);
  EXPECT_DOUBLE_EQ(s->power_kw, 3500.0 - 0.75 * 46.0);
  EXPECT_DOUBLE_EQ(s->bias_echo_pct, -0.75);
  ASSERT_TRUE(l.deactivate());
  const auto w = server.writes();
  ASSERT_FALSE(w.empty());
  EXPECT_EQ(w.back().control, 0);
  EXPECT_EQ(w.back().bias_raw, 0);
}

TEST(ModbusRtu, WrongUnitIsTimeout) {
  PtyPair pty;
  if (!pty.ok()) GTEST_SKIP() << "socat could not make a pty pair; RTU test skipped";
  drivers::testing::ModbusTestServer server(pty.plant(), 38400);
  auto o = rtu_options();
  o.response_timeout = 100ms;
  auto link = drivers::open_link("modbus+rtu:" + pty.rig() + "?baud=38400&unit=2", o);
  ASSERT_TRUE(link);
  ASSERT_TRUE(link.value()->configure());
  auto s = link.value()->read();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().kind, LinkErrorKind::kTimeout) << s.error().message();
}

TEST(ModbusRtu, MissingDeviceIsLinkLostAtConfigure) {
  auto link = drivers::open_link("modbus+rtu:/dev/does-not-exist?baud=19200");
  ASSERT_TRUE(link);
  auto r = link.value()->configure();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, LinkErrorKind::kLinkLost);
  EXPECT_NE(r.error().detail.find("No such file"), std::string::npos) << r.error().detail;
}
