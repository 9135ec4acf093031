// Renders a generated report in headless Chromium and checks that the page's script drew
// every chart (uPlot canvases present, data-charts-drawn set, no script error).
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "rig/report/bode_chart.hpp"
#include "rig/report/html_report.hpp"

namespace rig::report {
namespace {

std::string find_browser() {
  for (const char* name : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"}) {
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
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe.get())) > 0) out.append(buffer.data(), n);
  return out;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

HtmlReport sample_report() {
  HtmlReport page("Browser check");
  page.section("Correlations");
  std::vector<double> lag, r;
  for (int i = -50; i <= 150; ++i) {
    lag.push_back(0.01 * i);
    r.push_back(i < 0 ? 0.0 : std::exp(-0.02 * i) * std::sin(0.1 * i));
  }
  page.chart({"cross-correlation", "lag (s)", "r_yu", lag, {{"measured", r}, {"model", r, "", true}}});
  const auto f = log_space(0.05, 20.0, 60);
  BodeCurve model{"model"};
  std::vector<double> lo, hi;
  for (double fh : f) {
    const std::complex<double> s(0.0, 2 * M_PI * fh);
    model.response.push_back(11.0 / (0.07 * s * s + 0.19 * s + 11.05) * std::exp(-0.1 * s));
    lo.push_back(0.9 * std::abs(model.response.back()));
    hi.push_back(1.1 * std::abs(model.response.back()));
  }
  model.mag_lo = lo;
  model.mag_hi = hi;
  const auto [mag, phase] = bode_charts("Bode", f, {model});
  page.section("Bode").chart(mag).chart(phase);
  return page;
}

TEST(BrowserRender, ChromiumDrawsEveryChartWithoutScriptErrors) {
  const std::string browser = find_browser();
  if (browser.empty()) GTEST_SKIP() << "no chromium installed: cannot render the report";
  const auto dir = std::filesystem::temp_directory_path() / ("rig_report_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "profile");
  const HtmlReport page = sample_report();
  page.write(dir / "report.html");
  // --virtual-time-budget lets the page's scripts run to completion before the DOM dump.
  const std::string command =
      "timeout 90 " + browser +
      " --headless --no-sandbox --disable-gpu --disable-background-networking"
      " --disable-component-update --disable-sync --no-first-run --disable-dev-shm-usage"
      " --user-data-dir=" + (dir / "profile").string() +
      " --window-size=1200,2000 --virtual-time-budget=10000 --dump-dom file://" +
      (dir / "report.html").string() + " 2>/dev/null";
  const std::string dom = run(command);
  std::filesystem::remove_all(dir);
  ASSERT_FALSE(dom.empty()) << "chromium produced no DOM: " << command;
  EXPECT_EQ(dom.find("data-js-error=\""), std::string::npos) << dom.substr(0, 2000);
  EXPECT_NE(dom.find("data-charts-drawn=\"3\""), std::string::npos);
  EXPECT_GE(count_of(dom, "<canvas"), 3u) << "uPlot draws one canvas per chart";
  EXPECT_EQ(count_of(dom, "class=\"uplot"), 3u);
}

}  // namespace
}  // namespace rig::report
