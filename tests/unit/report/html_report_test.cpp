#include <cmath>
#include <regex>

#include <gtest/gtest.h>

#include "rig/report/bode_chart.hpp"
#include "rig/report/html_report.hpp"
#include "rig/report/json_out.hpp"
#include "rig/report/uplot_assets.hpp"

namespace rig::report {
namespace {

TEST(HtmlReport, EscapesTextEverywhere) {
  HtmlReport page("a < b & \"c\"");
  page.section("<script>alert(1)</script>").paragraph("x > y").key_values({{"k<", "v&"}});
  const std::string html = page.render();
  EXPECT_NE(html.find("<title>a &lt; b &amp; &quot;c&quot;</title>"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
  EXPECT_EQ(html.find("<script>alert(1)"), std::string::npos);
  EXPECT_NE(html.find("<td>k&lt;</td><td>v&amp;</td>"), std::string::npos);
}

TEST(HtmlReport, IsSelfContainedWithNoExternalReferences) {
  HtmlReport page("r");
  page.chart({"c", "x", "y", {1, 2, 3}, {{"s", {1, 4, 9}}}});
  const std::string html = page.render();
  EXPECT_NE(html.find(std::string(kUplotJs.substr(0, 200))), std::string::npos);
  EXPECT_NE(html.find(std::string(kUplotCss.substr(0, 100))), std::string::npos);
  EXPECT_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*["']?(https?:)?//)")));
  EXPECT_NE(html.find("data-charts-expected=\"1\""), std::string::npos);
}

TEST(HtmlReport, ChartDataCannotCloseTheScriptElement) {
  HtmlReport page("r");
  page.chart({"</script><b>", "x", "y", {1, 2}, {{"s", {1, 2}}}});
  const std::string html = page.render();
  EXPECT_EQ(html.find("</script><b>"), std::string::npos);
  EXPECT_NE(html.find("\\u003c/script>\\u003cb>"), std::string::npos);
}

TEST(HtmlReport, NonFiniteAndNonPositiveLogValuesBecomeGaps) {
  HtmlReport page("r");
  Chart c{"c", "f", "|H|", {1, 2, 3}, {{"s", {1.0, NAN, -1.0}}}};
  c.log_y = true;
  page.chart(c);
  EXPECT_NE(page.render().find("[1.0,null,null]"), std::string::npos);
}

TEST(HtmlReport, RejectsInconsistentCharts) {
  HtmlReport page("r");
  EXPECT_THROW(page.chart({"c", "x", "y", {1, 2, 3}, {{"s", {1, 2}}}}), std::invalid_argument);
  Chart log_zero{"c", "x", "y", {0, 1}, {{"s", {1, 2}}}};
  log_zero.log_x = true;
  EXPECT_THROW(page.chart(log_zero), std::invalid_argument);
  Chart bad_band{"c", "x", "y", {1, 2}, {{"s", {1, 2}}}};
  bad_band.bands.push_back({0, 3});
  EXPECT_THROW(page.chart(bad_band), std::invalid_argument);
  EXPECT_THROW(page.table({{"a", "b"}, {{"1"}}}), std::invalid_argument);
  EXPECT_EQ(page.chart_count(), 0u);
}

TEST(BodeChart, FirstOrderLagMagnitudeAndUnwrappedPhase) {
  const auto f = log_space(0.01, 100.0, 41);
  ASSERT_EQ(f.size(), 41u);
  EXPECT_NEAR(f.front(), 0.01, 1e-15);
  EXPECT_NEAR(f.back(), 100.0, 1e-12);
  BodeCurve curve{"H"};
  const double delay_s = 0.02;  // phase reaches -810 deg: must be unwrapped, steps < 180 deg
  for (double fh : f) {
    const std::complex<double> s(0.0, 2 * M_PI * fh);
    curve.response.push_back(std::exp(-delay_s * s) / (1.0 + s));
  }
  const auto [mag, phase] = bode_charts("G", f, {curve});
  ASSERT_EQ(mag.series.size(), 1u);
  EXPECT_TRUE(mag.log_x && mag.log_y && phase.log_x && !phase.log_y);
  EXPECT_NEAR(mag.series[0].y[0], 1.0 / std::hypot(1.0, 2 * M_PI * 0.01), 1e-12);
  const double f_last = f.back();
  const double expected_deg = -(std::atan(2 * M_PI * f_last) + delay_s * 2 * M_PI * f_last) * 180 / M_PI;
  EXPECT_NEAR(phase.series[0].y.back(), expected_deg, 1e-6);
}

TEST(BodeChart, UncertaintyBandAddsTwoEdgeSeriesAndABand) {
  const std::vector<double> f = {1, 2};
  BodeCurve c{"H", {{1, 0}, {0.5, 0}}, std::vector<double>{0.9, 0.4}, std::vector<double>{1.1, 0.6}};
  const auto [mag, phase] = bode_charts("G", f, {c});
  ASSERT_EQ(mag.series.size(), 3u);
  ASSERT_EQ(mag.bands.size(), 1u);
  EXPECT_EQ(mag.series[mag.bands[0].upper].y[0], 1.1);
  EXPECT_EQ(mag.series[mag.bands[0].lower].y[1], 0.4);
  EXPECT_EQ(phase.series.size(), 1u);
}

TEST(JsonOut, NonFiniteNumbersBecomeNull) {
  const Eigen::VectorXd v = (Eigen::VectorXd(3) << 1.5, NAN, INFINITY).finished();
  EXPECT_EQ(to_json_array(v).dump(), "[1.5,null,null]");
  EXPECT_EQ(to_json_matrix(Eigen::MatrixXd::Identity(2, 2)).dump(), "[[1.0,0.0],[0.0,1.0]]");
}

}  // namespace
}  // namespace rig::report
