// Tables of numbers (table_file.hpp), and one number syntax for every text input: the same
// spellings read as the same doubles in logs, orientation files and tables (issue 17: `+1` was
// a number in logs, not in orientation files, and tables used strtod).
#include <string>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/orientation_file.hpp"
#include "accelcal/table_file.hpp"

namespace accelcal {
namespace {

std::string ErrorOf(const std::string& text, std::size_t columns) {
  try {
    ParseNumberTable(text, "t.csv", columns);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(NumberTable, HeaderCommentsBlankLinesAndEitherDelimiter) {
  const auto rows = ParseNumberTable(
      "theta1_deg,theta2_deg,ax\n# the coarse stage\n\n0, 90, 9.8\r\n+1 -2.5e1 0  # no\n", "t.csv",
      3);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0], (std::vector<double>{0, 90, 9.8}));
  EXPECT_EQ(rows[1], (std::vector<double>{1, -25, 0}));
}

TEST(NumberTable, RowsAndErrorsNameTheirLine) {
  const auto rows = ParseNumberTable("a b c\n1 2 3\n+4,-5, 6e0\n", "t.csv", 3);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1], (std::vector<double>{4, -5, 6}));
  EXPECT_EQ(ErrorOf("1,2,3\n4,5\n", 3), "t.csv:2: expected 3 numbers");
  EXPECT_EQ(ErrorOf("1,2,3\nx,y,z\n", 3), "t.csv:2: expected 3 numbers");  // a header only first
  EXPECT_EQ(ErrorOf("1,2,nan\n", 3), "t.csv:1: a value is not finite");
  EXPECT_EQ(ErrorOf("1,2,1e999\n", 3), "t.csv:1: a value is not finite");
  EXPECT_EQ(ErrorOf("# nothing\n\n", 3), "t.csv: no rows");
  EXPECT_EQ(ErrorOf("a,b,c\n", 3), "t.csv: no rows");
  EXPECT_EQ(ErrorOf(std::string("1,2,3\n\0\n", 8), 3).rfind("t.csv:2: a NUL byte", 0), 0u);
}

TEST(NumberSyntax, OneSpellingOneValueInEveryTextInput) {
  for (const char* spelling : {"+1", "1", "1.0", "1e0", "+1.000", "0.1e1"}) {
    const std::string s = spelling;
    // A table.
    EXPECT_EQ(ParseNumberTable(s + ",0,0\n", "t.csv", 3)[0][0], 1.0) << s;
    // An orientation file (directions are normalised: check the raw value through a unit x).
    const OrientationFile o = ParseOrientations(s + ",0,0\n", "o.csv");
    ASSERT_EQ(o.directions.size(), 1u) << s;
    EXPECT_EQ(o.directions[0].x(), 1.0) << s;
    // A positions file.
    ReadOptions options;
    options.kind = InputKind::kPositions;
    const InputData p = ParseInput("x,y,z\n" + s + ",0,0\n", "p.csv", options);
    ASSERT_EQ(p.positions.size(), 1u) << s;
    EXPECT_EQ(p.positions[0].mean.x(), 1.0) << s;
  }
  // And what none of them takes.
  for (const char* spelling : {"++1", "+-1", "1,0", "0x1", "1 e0", "one"}) {
    const std::string s = spelling;
    EXPECT_THROW(ParseNumberTable("1 0 0\n" + s + " 0 0\n", "t.csv", 3), InputError) << s;
    EXPECT_THROW(ParseOrientations("0,0,1\n" + s + " 0 0\n", "o.csv"), InputError) << s;
  }
}

}  // namespace
}  // namespace accelcal
