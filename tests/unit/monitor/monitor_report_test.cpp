// report.json and report.html of a monitor history.
#include "rig/monitor/monitor_report.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/unit/monitor/monitor_history_sample.hpp"
#include "tests/unit/monitor/test_dir.hpp"

namespace rig::monitor {
namespace {

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(MonitorReport, WritesJsonAndHtmlWithEveryRunAlarmAndSeries) {
  TempDir dir;
  const auto file = dir / "monitor.db";
  write_sample_history(file, 250);
  const History h = History::open_read_only(file);
  write_monitor_report(h, dir / "out");
  const auto doc = nlohmann::json::parse(read_text(dir / "out" / "report.json"));
  EXPECT_EQ(doc["command"], "monitor report");
  EXPECT_EQ(doc["counts"]["runs"], 2);
  EXPECT_EQ(doc["runs"].size(), 2u);
  EXPECT_EQ(doc["runs"][1]["offset_s"], doc["runs"][0]["duration_s"]);
  EXPECT_TRUE(doc["runs"][1]["exit_code"].is_null());
  EXPECT_EQ(doc["alarms"].size(), 1u);
  EXPECT_EQ(doc["alarms"][0]["cause"], "injector/cylinder loss");
  EXPECT_EQ(doc["alarms"][0]["evidence"]["z"], 4.2);
  EXPECT_EQ(doc["events"].size(), 251u);  // and the trip
  ASSERT_EQ(doc["series"].size(), 2u);
  for (const auto& s : doc["series"]) {
    EXPECT_GT(s["count"].get<std::size_t>(), kReportPoints) << s["name"];
    EXPECT_EQ(s["points"]["shown"], kReportPoints);
    EXPECT_EQ(s["points"]["value"].size(), kReportPoints);
    EXPECT_EQ(s["points"]["hi"].size(), kReportPoints);
  }
  EXPECT_TRUE(doc["series"][0]["points"]["lo"][0].is_null()) << "fn_hz has no thresholds";
  EXPECT_EQ(doc["series"][1]["points"]["lo"][0], -1.0);
  EXPECT_DOUBLE_EQ(doc["total_monitored_s"].get<double>(),
                   doc["series"][1]["last_history_s"].get<double>());

  const std::string html = read_text(dir / "out" / "report.html");
  EXPECT_NE(html.find("injector/cylinder loss"), std::string::npos);
  EXPECT_NE(html.find("Check the injectors."), std::string::npos);
  EXPECT_NE(html.find("The last 200 of 251 events"), std::string::npos);
  EXPECT_NE(html.find("event 51<"), std::string::npos);
  EXPECT_EQ(html.find("event 50<"), std::string::npos) << "older events only in report.json";
  EXPECT_NE(html.find("lo threshold"), std::string::npos);
}

TEST(MonitorReport, AnEmptyHistoryStillGivesBothFiles) {
  TempDir dir;
  const auto file = dir / "monitor.db";
  { History::open(file); }
  write_monitor_report(History::open_read_only(file), dir / "out");
  const auto doc = nlohmann::json::parse(read_text(dir / "out" / "report.json"));
  EXPECT_EQ(doc["counts"]["runs"], 0);
  EXPECT_EQ(doc["total_monitored_s"], 0.0);
  EXPECT_NE(read_text(dir / "out" / "report.html").find("No alarm was raised."), std::string::npos);
}

}  // namespace
}  // namespace rig::monitor
