// Every defect gives one line naming the file, the line, the column and what was expected.
#include <gtest/gtest.h>

#include "rig/io/recording.hpp"

namespace rig::io {
namespace {

struct Expected {
  long line;
  std::string column;
  std::string words;  // a fragment of the message
};

void expect_error(const std::string& text, const Expected& expected, ReadOptions options = {}) {
  try {
    parse_recording(text, "rec.csv", options);
    FAIL() << "expected InputError for:\n" << text;
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(e.file(), "rec.csv");
    EXPECT_EQ(e.line(), expected.line) << message;
    EXPECT_EQ(e.column(), expected.column) << message;
    EXPECT_NE(message.find(expected.words), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
    EXPECT_EQ(message.rfind("rec.csv", 0), 0u) << message;
  }
}

TEST(RecordingErrors, EmptyFile) { expect_error("", {0, "", "empty"}); }
TEST(RecordingErrors, BlankOnlyFile) { expect_error("\n\n  \n", {0, "", "empty"}); }

TEST(RecordingErrors, NonNumericCell) {
  expect_error("t,u,y\n0,1,2\n0.1,abc,3\n", {3, "u", "expected a number, found \"abc\""});
}

TEST(RecordingErrors, NanAndInfCells) {
  expect_error("t,u,y\n0,1,2\n0.1,1,nan\n", {3, "y", "finite"});
  expect_error("t,u,y\n0,1,2\n0.1,-inf,1\n", {3, "u", "finite"});
  expect_error("t,u,y\n0,1,2\n0.1,1e999,1\n", {3, "u", "finite"});
}

TEST(RecordingErrors, EmptyCellInTheMiddle) {
  expect_error("t,u,y\n0,1,2\n0.1,,3\n0.2,1,3\n", {3, "u", "empty cell"});
}

TEST(RecordingErrors, MissingColumnListsThoseAvailable) {
  ReadOptions options;
  options.columns = {"power_kw"};
  expect_error("t,u,y\n0,1,2\n0.1,1,3\n", {0, "power_kw", "missing column (the file has: t, u, y)"},
               options);
}

TEST(RecordingErrors, TooFewRows) {
  ReadOptions options;
  options.min_rows = 64;
  expect_error("t,u,y\n0,1,2\n0.1,1,3\n", {0, "", "expected at least 64 data rows, found 2"},
               options);
  expect_error("t,u,y\n", {0, "", "found 0"});
}

TEST(RecordingErrors, WrongFieldCount) {
  expect_error("t,u,y\n0,1,2\n0.1,1\n", {3, "", "expected 3 fields, found 2"});
}

TEST(RecordingErrors, BlankLineInsideData) {
  expect_error("t,u,y\n0,1,2\n\n0.1,1,3\n", {3, "", "blank line"});
}

TEST(RecordingErrors, TimeNotIncreasing) {
  expect_error("t,u,y\n0,1,2\n0.1,1,3\n0.1,1,3\n", {4, "t", "increasing time"});
}

TEST(RecordingErrors, NoTimeBase) {
  expect_error("u,y\n1,2\n1,3\n", {0, "", "--dt"});
}

TEST(RecordingErrors, DuplicateHeaderName) {
  expect_error("t,u,u\n0,1,2\n1,1,3\n", {1, "u", "unique"});
}

TEST(RecordingErrors, SelectedScalarLikeColumnIsAnEmptyCell) {
  ReadOptions options;
  options.columns = {"u", "y"};
  expect_error("t,u,y\n0,1,2\n1,,\n2,,\n", {3, "u", "empty cell"}, options);
}

}  // namespace
}  // namespace rig::io
