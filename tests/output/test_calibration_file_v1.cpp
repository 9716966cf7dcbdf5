// Version-1 calibration files (tests/data/calibration-v1, written by the last main that wrote
// them) read as the version-2 file with the same accelerometer section reads: the same typed
// values, the same exports, the same report. Their bytes differ only in where the keys are.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/report.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

namespace fs = std::filesystem;
using nlohmann::ordered_json;

std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The version-2 document of a version-1 one: its keys but format and version under
// sensors.accelerometer, its verdict also at the top, an empty provenance.
ordered_json AsVersion2(ordered_json v1) {
  ordered_json v2;
  v2["format"] = v1["format"];
  v2["version"] = 2;
  v2["verdict"] = v1["verdict"];
  v1.erase("format");
  v1.erase("version");
  v2["sensors"]["accelerometer"] = v1;
  v2["provenance"] = ordered_json::object();
  return v2;
}

void ExpectSameFindings(const std::vector<Finding>& a, const std::vector<Finding>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].code, b[i].code);
    EXPECT_EQ(a[i].severity, b[i].severity);
    EXPECT_EQ(a[i].message, b[i].message);
    ASSERT_EQ(a[i].numbers.size(), b[i].numbers.size());
    for (std::size_t j = 0; j < a[i].numbers.size(); ++j) {
      EXPECT_EQ(a[i].numbers[j].first, b[i].numbers[j].first);
      const double x = a[i].numbers[j].second, y = b[i].numbers[j].second;
      EXPECT_TRUE(x == y || (std::isnan(x) && std::isnan(y))) << a[i].code;
    }
  }
}

TEST(CalibrationFileVersion1, ReadsAsTheVersion2FileWithTheSameSection) {
  const fs::path dir = fs::path(ACCELCAL_SOURCE_DIR) / "tests/data/calibration-v1";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    SCOPED_TRACE(entry.path().filename().string());
    const std::string text = Slurp(entry.path());
    const ordered_json doc = ordered_json::parse(text);
    ASSERT_EQ(doc["version"], 1);
    const LoadedCalibration v1 = ParseCalibrationJson(text, "v1.json");
    const std::string text2 = AsVersion2(doc).dump(2);
    const LoadedCalibration v2 = ParseCalibrationJson(text2, "v2.json");
    EXPECT_EQ(v1.version, 1);
    EXPECT_EQ(v2.version, 2);
    EXPECT_EQ(v1.model, v2.model);
    EXPECT_EQ(v1.frame, v2.frame);
    EXPECT_EQ(v1.params.K, v2.params.K);
    EXPECT_EQ(v1.params.bias, v2.params.bias);
    EXPECT_EQ(v1.params.k2, v2.params.k2);
    EXPECT_EQ(v1.gravity, v2.gravity);
    EXPECT_EQ(v1.unit, v2.unit);
    EXPECT_EQ(v1.raw_unit, v2.raw_unit);
    EXPECT_EQ(v1.source, v2.source);
    EXPECT_EQ(v1.verdict, doc["verdict"]);
    EXPECT_EQ(v1.verdict, v2.verdict);
    EXPECT_EQ(v1.covariance, v2.covariance);
    EXPECT_EQ(v1.position_means, v2.position_means);
    ASSERT_EQ(v1.positions.size(), doc["positions"].size());
    ASSERT_TRUE(v1.diagnostics && v2.diagnostics);
    ExpectSameFindings(*v1.diagnostics, *v2.diagnostics);
    EXPECT_EQ(v1.solver.iterations, v2.solver.iterations);
    EXPECT_TRUE(v1.provenance.accelcal_version.empty());
    // Every export and the report: the same bytes (the native JSON export is the file itself).
    for (const ExportFormat format : AllExportFormats()) {
      if (format == ExportFormat::kJson || format == ExportFormat::kYaml) continue;
      std::string a, b;
      try {
        a = ExportCalibration(v1, text, format).text;
      } catch (const DataError& e) {
        a = e.what();
      }
      try {
        b = ExportCalibration(v2, text2, format).text;
      } catch (const DataError& e) {
        b = e.what();
      }
      EXPECT_EQ(a, b) << ToString(format);
    }
    EXPECT_EQ(RenderReport({v1, "cal.json", nullptr, {}}),
              RenderReport({v2, "cal.json", nullptr, {}}));
  }
  EXPECT_EQ(files, 5);
}

}  // namespace
}  // namespace accelcal
