#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "rig/session/live_view.hpp"

namespace rig::session {
namespace {

TEST(LiveView, BarPlacesTheDeviationWithinTheBand) {
  EXPECT_EQ(deviation_bar(0.0, 3.0, 11), "[-----#-----]");
  EXPECT_EQ(deviation_bar(3.0, 3.0, 11), "[-----|----#]");
  EXPECT_EQ(deviation_bar(-1.2, 3.0, 11), "[---#-|-----]");
  EXPECT_EQ(deviation_bar(4.0, 3.0, 11), "[-----|---->]");
  EXPECT_EQ(deviation_bar(-9.0, 3.0, 11), "[<----|-----]");
}

TEST(LiveView, StatusLineCarriesEtaEstimatesAndFlags) {
  LiveStatus s;
  s.phase = "excite";
  s.elapsed_s = 75.0;
  s.eta_s = 30.0;
  s.deviation_pct = 1.2;
  s.estimates = {{"q2", 0.07, 0.004}};
  s.flags = {"backoff"};
  const std::string line = format_status(s);
  EXPECT_NE(line.find("01:15"), std::string::npos) << line;
  EXPECT_NE(line.find("ETA 00:30"), std::string::npos) << line;
  EXPECT_NE(line.find("q2 0.07+-0.004"), std::string::npos) << line;
  EXPECT_NE(line.find("! backoff"), std::string::npos) << line;
  EXPECT_EQ(line.find('\n'), std::string::npos);
}

TEST(LiveView, PlainOutputIsRateLimitedByTestTime) {
  char* buf = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buf, &size);
  LiveView view(out, false, 1.0);
  LiveStatus s;
  for (int i = 0; i < 300; ++i) {  // 3 s at 100 Hz -> 3 lines
    s.elapsed_s = i * 0.01;
    view.update(s);
  }
  std::fclose(out);
  const std::string text(buf, size);
  std::free(buf);
  int lines = 0;
  for (char c : text) lines += c == '\n';
  EXPECT_EQ(lines, 3) << text;
  EXPECT_EQ(text.find('\r'), std::string::npos);
}

}  // namespace
}  // namespace rig::session
