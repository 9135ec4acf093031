// Exit codes and one-line messages of `rig identify` for bad input (DESIGN.md section 4).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "cli_runner.hpp"

namespace rig {
namespace {

using testing::run_rig;
using testing::scratch;

std::string sine_rows(int n, bool constant_input = false) {
  std::string text = "t,u,y\n";
  for (int i = 0; i < n; ++i) {
    const double u = constant_input ? 1.0 : std::sin(0.37 * i) + std::sin(1.3 * i);
    text +=
        std::to_string(0.01 * i) + "," + std::to_string(u) + "," + std::to_string(0.5 * u) + "\n";
  }
  return text;
}

struct BadCase {
  const char* name;
  std::string text;
  std::string extra_args;
  std::string words;  // fragment of the one-line message
};

TEST(IdentifyErrors, BadInputsExitWithTwoAndOneLineNamingTheFile) {
  std::string nan_rows = sine_rows(300);
  nan_rows.replace(nan_rows.find('\n', 200) + 1, 0, "1.5,nan,2\n");
  std::string text_rows = sine_rows(300);
  text_rows.replace(text_rows.find('\n', 200) + 1, 0, "1.5,abc,2\n");
  const std::vector<BadCase> cases = {
      {"empty", "", "", "empty"},
      {"non_numeric", text_rows, "", "expected a number, found \"abc\""},
      {"nan", nan_rows, "", "finite"},
      {"missing_column", sine_rows(300), "--input u --output power_kw", "missing column"},
      {"too_few_samples", sine_rows(50), "", "expected at least 128 data rows"},
      {"too_few_for_lags", sine_rows(300), "--lags 100", "4 x --lags"},
      {"constant_input", sine_rows(300, true), "", "constant"},
      {"bad_order", sine_rows(300), "--order 2/3", "--order"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto dir = scratch(c.name);
    std::ofstream(dir / "rec.csv") << c.text;
    const auto r = run_rig("identify --recording " + (dir / "rec.csv").string() + " " +
                               c.extra_args + " --out " + (dir / "out").string(),
                           dir);
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find(c.words), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
    if (std::string(c.name) != "bad_order") {
      EXPECT_NE(r.err.find("rec.csv"), std::string::npos) << r.err;
    }
  }
}

TEST(IdentifyErrors, MissingFileAndUsageErrorsExitWithTwo) {
  const auto dir = scratch("usage");
  EXPECT_EQ(
      run_rig("identify --recording " + (dir / "nope.csv").string() + " --out " + dir.string(), dir)
          .exit_code,
      2);
  EXPECT_EQ(run_rig("identify --out " + dir.string(), dir).exit_code, 2)
      << "--recording is required";
  EXPECT_EQ(run_rig("identify --recording x.csv --out d --method magic", dir).exit_code, 2);
  EXPECT_EQ(run_rig("no-such-command", dir).exit_code, 2);
  EXPECT_EQ(run_rig("", dir).exit_code, 2) << "a subcommand is required";
}

TEST(IdentifyErrors, HelpExitsWithZero) {
  const auto dir = scratch("help");
  const auto top = run_rig("--help", dir);
  EXPECT_EQ(top.exit_code, 0);
  EXPECT_NE(top.out.find("identify"), std::string::npos);
  const auto sub = run_rig("identify --help", dir);
  EXPECT_EQ(sub.exit_code, 0);
  EXPECT_NE(sub.out.find("--recording"), std::string::npos);
  EXPECT_NE(sub.out.find("--columns"), std::string::npos);
}

TEST(IdentifyErrors, UnrelatedOutputFailsWithOneAndNamesTheCheck) {
  const auto dir = scratch("unrelated");
  std::string text = "t,u,y\n";
  for (int i = 0; i < 4000; ++i) {  // y is a different deterministic sequence than u
    text += std::to_string(0.01 * i) + "," +
            std::to_string(std::sin(0.37 * i) + std::sin(1.31 * i) + std::sin(2.9 * i) +
                           std::sin(0.11 * i)) +
            "," +
            std::to_string(std::sin(0.523 * i * i * 1e-3) + std::cos(2.1 * i + 0.002 * i * i)) +
            "\n";
  }
  std::ofstream(dir / "rec.csv") << text;
  const auto r = run_rig(
      "identify --recording " + (dir / "rec.csv").string() + " --out " + (dir / "out").string(),
      dir);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("does not respond"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace rig
