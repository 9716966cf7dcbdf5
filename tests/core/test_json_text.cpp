// The one JSON writer (json_text.hpp): layout, numbers, escaping, and that what it writes parses
// back to the same document.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/json_text.hpp"

namespace accelcal {
namespace {

using Json = nlohmann::ordered_json;

TEST(JsonText, LayoutIsOneMemberPerLineAtTheTopAndFlatContainersOnOneLine) {
  Json doc;
  doc["name"] = "x";
  doc["vector"] = {1.5, -2, 0.1};
  doc["matrix"] = {{1, 0}, {0, 1}};
  doc["record"] = {{"value", 0.25}, {"std", 0.5}};
  doc["rows"] = {{{"begin", 1}, {"mean", {1, 2}}}, {{"begin", 2}, {"mean", {3, 4}}}};
  doc["empty"] = Json::array();
  EXPECT_EQ(JsonText(doc),
            "{\n"
            "  \"name\": \"x\",\n"
            "  \"vector\": [1.5, -2, 0.1],\n"
            "  \"matrix\": [[1, 0], [0, 1]],\n"
            "  \"record\": {\"value\": 0.25, \"std\": 0.5},\n"
            "  \"rows\": [\n"
            "    {\"begin\": 1, \"mean\": [1, 2]},\n"
            "    {\"begin\": 2, \"mean\": [3, 4]}\n"
            "  ],\n"
            "  \"empty\": []\n"
            "}\n");
}

TEST(JsonText, NumbersAreShortestRoundTripAndNonFiniteIsNull) {
  const Json doc = {0.1,
                    1e300,
                    100.0,
                    -0.0,
                    5e-324,
                    12345678901234567.0,
                    7,
                    std::numeric_limits<double>::quiet_NaN(),
                    std::numeric_limits<double>::infinity()};
  // The top level is one member per line even when flat.
  EXPECT_EQ(JsonText(doc),
            "[\n  0.1,\n  1e+300,\n  100,\n  -0,\n  5e-324,\n  12345678901234568,\n  7,\n  null,\n"
            "  null\n]\n");
  const Json back = Json::parse(JsonText(doc));
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(back[i].get<double>(), doc[i].get<double>()) << i;
  }
}

TEST(JsonText, StringsAreEscapedAndInvalidUtf8Replaced) {
  // The defect of issue 17: `detect --json` wrote a path containing '"' unescaped.
  Json doc;
  doc["path"] =
      "a\"b\\c\nd\te\x01"
      "f";
  doc["bad"] = std::string("ok\xff");
  const std::string text = JsonText(doc);
  EXPECT_EQ(text,
            "{\n  \"path\": \"a\\\"b\\\\c\\nd\\te\\u0001f\",\n  \"bad\": \"ok\xef\xbf\xbd\"\n}\n");
  EXPECT_EQ(Json::parse(text)["path"], doc["path"]);
}

}  // namespace
}  // namespace accelcal
