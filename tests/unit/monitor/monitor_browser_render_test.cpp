// Renders a monitor report in headless Chromium and checks that the page's script drew every
// trend chart (data-charts-drawn set, uPlot canvases present, no script error).
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "rig/monitor/monitor_report.hpp"
#include "tests/unit/monitor/monitor_history_sample.hpp"
#include "tests/unit/monitor/test_dir.hpp"

namespace rig::monitor {
namespace {

std::string find_browser() {
  for (const char* name :
       {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"}) {
    if (::access(name, X_OK) == 0) return name;
  }
  return "";
}

std::string run(const std::string& command) {
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen(command.c_str(), "r"), ::pclose);
  if (!pipe) return out;
  std::array<char, 65536> buffer{};
  std::size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe.get())) > 0)
    out.append(buffer.data(), n);
  return out;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1))
    ++n;
  return n;
}

TEST(MonitorReportRender, ChromiumDrawsEveryTrendWithoutScriptErrors) {
  const std::string browser = find_browser();
  if (browser.empty()) GTEST_SKIP() << "no chromium installed: cannot render the report";
  TempDir dir;
  write_sample_history(dir / "monitor.db", 5);
  write_monitor_report(History::open_read_only(dir / "monitor.db"), dir / "out");
  std::filesystem::create_directories(dir / "profile");
  // --virtual-time-budget lets the page's scripts run to completion before the DOM dump.
  const std::string command =
      "timeout 90 " + browser +
      " --headless --no-sandbox --disable-gpu --disable-background-networking"
      " --disable-component-update --disable-sync --no-first-run --disable-dev-shm-usage"
      " --user-data-dir=" +
      (dir / "profile").string() +
      " --window-size=1200,2000 --virtual-time-budget=10000 --dump-dom file://" +
      (dir / "out" / "report.html").string() + " 2>/dev/null";
  const std::string dom = run(command);
  ASSERT_FALSE(dom.empty()) << "chromium produced no DOM: " << command;
  EXPECT_EQ(dom.find("data-js-error=\""), std::string::npos) << dom.substr(0, 2000);
  EXPECT_NE(dom.find("data-charts-drawn=\"2\""), std::string::npos);
  EXPECT_EQ(count_of(dom, "class=\"uplot"), 2u);
  EXPECT_GE(count_of(dom, "<canvas"), 2u) << "uPlot draws one canvas per chart";
}

}  // namespace
}  // namespace rig::monitor
