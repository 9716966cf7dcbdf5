// The library in a decimal-comma locale (issue 16): a host program that sets the C locale's
// LC_NUMERIC (a Python GUI calling setlocale) or the C++ global locale to de_DE.UTF-8 changes no
// byte the library writes and no number it reads. The locale must be installed (a failure, not a
// skip, when it is not): scripts/install-deps.sh generates it.
#include <locale.h>

#include <cctype>
#include <clocale>
#include <cstdio>
#include <locale>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/export.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/report.hpp"
#include "accelcal/series_file.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/static_detection.hpp"
#include "support/paths.hpp"
#include "support/sample_noise.hpp"

namespace accelcal {
namespace {

constexpr const char* kCommaLocale = "de_DE.UTF-8";
const std::string kXsens = std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/xsens_acc.mat";

// Runs `f` with the C++ global locale (and with it the C locale, all categories) and the C
// locale's LC_NUMERIC set to de_DE.UTF-8, as a host program sets them; the classic "C" locales
// again afterwards, also when f throws.
template <typename Function>
auto InCommaLocale(Function f) {
  struct Restore {
    ~Restore() {
      std::locale::global(std::locale::classic());
      std::setlocale(LC_ALL, "C");
    }
  } restore;
  std::locale::global(std::locale(kCommaLocale));
  std::setlocale(LC_NUMERIC, kCommaLocale);
  return f();
}

// A digit, a comma, a digit: a decimal comma (the texts checked with it separate numbers by ", ",
// tabs or line ends).
bool HasDecimalComma(const std::string& text) {
  for (std::size_t i = 1; i + 1 < text.size(); ++i) {
    if (text[i] == ',' && std::isdigit(static_cast<unsigned char>(text[i - 1])) &&
        std::isdigit(static_cast<unsigned char>(text[i + 1]))) {
      return true;
    }
  }
  return false;
}

class DecimalComma : public ::testing::Test {
 protected:
  void SetUp() override {
    const locale_t comma = newlocale(LC_ALL_MASK, kCommaLocale, locale_t{});
    ASSERT_NE(comma, locale_t{}) << "the locale " << kCommaLocale
                                 << " is not installed: scripts/install-deps.sh generates it";
    freelocale(comma);
    // The premise: in it, printf and iostreams write a decimal comma.
    const std::string printf_text = InCommaLocale([] {
      char buf[16];
      std::snprintf(buf, sizeof buf, "%.1f", 0.5);
      return std::string(buf);
    });
    ASSERT_EQ(printf_text, "0,5");
    const std::string stream_text = InCommaLocale([] {
      std::ostringstream out;
      out << 0.5;
      return out.str();
    });
    ASSERT_EQ(stream_text, "0,5");
  }
};

// A quadratic MEMS device in g with raw readings in g, 24 noisy positions with their sample noise.
struct Simulated {
  std::vector<Position> positions;
  CalibrationResult result;
  CalibrationFileInfo info;
};
Simulated Simulate() {
  ModelParameters truth;
  truth.K << 1.02, 0, 0, 0.01, 0.98, 0, -0.02, 0.015, 1.01;
  truth.bias << 0.03, -0.02, 0.05;
  truth.k2 << 0.01, -0.008, 0.012;
  Simulated s;
  for (const Vec3& p : SimulatePositions(truth, 1.0, RandomDirectionsInCap(24, 3.14159, 7),
                                         Vec3::Constant(1e-3), 8)) {
    // Samples' noise 10 times too small for the positions' scatter: a `scatter_ratio` finding
    // (6.92).
    s.positions.push_back(Position{p, 400, Vec3::Constant(2e-3), std::nullopt, std::nullopt});
  }
  CalibrationOptions options;
  options.model = ModelKind::kQuadratic;
  options.gravity = 1.0;
  options.reading_sigmas = SigmasOfMeans(s.positions);
  s.result = Calibrate(Means(s.positions), options);
  s.info.unit = ForceUnit::kStandardGravity;
  s.info.raw_unit = "g";
  s.info.source = "simulated.csv";
  s.info.positions = s.positions;
  return s;
}

TEST_F(DecimalComma, EveryExportIsTheSameBytes) {
  const Simulated s = Simulate();
  const std::string json = CalibrationToJson(s.result, s.info);
  const LoadedCalibration cal = ParseCalibrationJson(json, "cal.json");
  for (const ExportFormat format : AllExportFormats()) {
    if (format == ExportFormat::kCHeader) continue;  // the quadratic model in x-first: below
    ExportOptions options;
    options.noise = test::SampleNoise();  // the noise formats need one
    const ExportResult c = ExportCalibration(cal, json, format, options);
    const ExportResult comma =
        InCommaLocale([&] { return ExportCalibration(cal, json, format, options); });
    EXPECT_EQ(comma.text, c.text) << ToString(format);
    EXPECT_EQ(comma.convention, c.convention) << ToString(format);
    EXPECT_FALSE(HasDecimalComma(c.text)) << ToString(format);
    EXPECT_EQ(comma.loss.max_error, c.loss.max_error) << ToString(format);
  }
  // PX4 and ArduPilot write their values with printf's %.9g, the conventions %.6g: the bug of
  // issue 16 ("INS_ACCSCAL_X,0,000208474897").
  const ExportResult ardupilot =
      InCommaLocale([&] { return ExportCalibration(cal, json, ExportFormat::kArduPilot); });
  EXPECT_NE(ardupilot.text.find("\nINS_ACCSCAL_X,"), std::string::npos) << ardupilot.text;
  EXPECT_NE(ardupilot.convention.find("offset = b * 9.80665, scale_i = 1 / K_ii"),
            std::string::npos)
      << ardupilot.convention;
  const ExportResult header = InCommaLocale([&] {
    ExportOptions o;
    o.c_prefix = "imu";
    return ExportCalibration(cal, json, ExportFormat::kCHeader, o);
  });
  EXPECT_FALSE(HasDecimalComma(header.text));
  ExportOptions o;
  o.c_prefix = "imu";
  EXPECT_EQ(header.text, ExportCalibration(cal, json, ExportFormat::kCHeader, o).text);
}

TEST_F(DecimalComma, CalibrationFileIsTheSameBytesAndReadsBackExactly) {
  const Simulated s = Simulate();
  // Written: the numbers (nlohmann's own conversion) and the diagnosis' messages (printf).
  const std::string c = CalibrationToJson(s.result, s.info);
  const std::string comma = InCommaLocale([&] { return CalibrationToJson(s.result, s.info); });
  EXPECT_EQ(comma, c);
  EXPECT_NE(c.find("\"message\": \"the positions scatter 6.92 times"), std::string::npos) << c;
  // Read: nlohmann's parser converts with strtod, which follows the C locale.
  const LoadedCalibration read = InCommaLocale([&] { return ParseCalibrationJson(c, "cal.json"); });
  EXPECT_EQ(read.params.K, s.result.params.K);
  EXPECT_EQ(read.params.bias, s.result.params.bias);
  EXPECT_EQ(read.params.k2, s.result.params.k2);
  EXPECT_EQ(read.gravity, 1.0);
  EXPECT_EQ(read.covariance, s.result.covariance);
  ASSERT_EQ(read.position_means.size(), s.positions.size());
  for (std::size_t k = 0; k < s.positions.size(); ++k) {
    EXPECT_EQ(read.position_means[k], s.positions[k].mean) << k;
  }
  // A number with a fraction, as a person writes it in a file.
  std::string edited = c;
  const std::string gravity = "\"gravity\": 1,";  // JsonText: a whole double as an integer
  ASSERT_NE(edited.find(gravity), std::string::npos);
  edited.replace(edited.find(gravity), gravity.size(), "\"gravity\": 0.98765432109876543,");
  const LoadedCalibration edited_read =
      InCommaLocale([&] { return ParseCalibrationJson(edited, "cal.json"); });
  EXPECT_EQ(edited_read.gravity, 0.98765432109876543);
}

TEST_F(DecimalComma, DiagnosisModelSelectionAndReportAreTheSameBytes) {
  // The Xsens recording: findings about its time column and its positions' scatter, with numbers.
  const InputData data = ReadInput(kXsens, {});
  const StaticDetectionResult detection = DetectStaticIntervals(data.raw, {});
  const std::vector<Position> positions = PositionsFromIntervals(detection.intervals);
  CalibrationOptions options;
  options.gravity = 9.81744;
  options.reading_sigmas = SigmasOfMeans(positions);
  const CalibrationResult result = Calibrate(Means(positions), options);
  const ModelSelection selection = SelectModel(Means(positions), options);
  const ModelSelection comma_selection =
      InCommaLocale([&] { return SelectModel(Means(positions), options); });
  EXPECT_EQ(comma_selection.reason, selection.reason);
  EXPECT_NE(selection.reason.find("held-out rms |f|-g 0.0"), std::string::npos) << selection.reason;

  const DiagnosisInput input{&result,
                             &positions,
                             OutlierOptions{}.max_excluded,
                             &selection,
                             {{"xsens", &data.raw, &detection}},
                             ForceUnit::kMetersPerSecond2};
  const Diagnosis c = Diagnose(input);
  const Diagnosis comma = InCommaLocale([&] { return Diagnose(input); });
  ASSERT_EQ(comma.findings.size(), c.findings.size());
  std::vector<std::string> codes;
  for (std::size_t i = 0; i < c.findings.size(); ++i) {
    codes.push_back(c.findings[i].code);
    EXPECT_EQ(comma.findings[i].message, c.findings[i].message);
    EXPECT_FALSE(HasDecimalComma(comma.findings[i].message)) << comma.findings[i].message;
  }
  EXPECT_EQ(codes, (std::vector<std::string>{"scatter_ratio", "time_unit"}));
  EXPECT_NE(c.findings[0].message.find("scatter 4.57 times"), std::string::npos)
      << c.findings[0].message;

  CalibrationFileInfo info;
  info.raw_unit = "counts";
  info.source = kXsens;
  info.positions = positions;
  info.model_selection = &selection;
  info.diagnosis = &c;
  ReportInput report;
  report.calibration_name = "xsens.json";
  report.calibration = ParseCalibrationJson(CalibrationToJson(result, info), "xsens.json");
  report.log = &data.raw;
  report.rejected = detection.rejected;
  const std::string html = RenderReport(report);
  EXPECT_EQ(InCommaLocale([&] { return RenderReport(report); }), html);
  EXPECT_NE(html.find("<rect class=\"frame\" x=\"70.0\""), std::string::npos);
}

TEST_F(DecimalComma, LogsAndSeriesReadPointNumbersExactly) {
  const InputData log = InCommaLocale([] {
    ReadOptions read;
    read.kind = InputKind::kRaw;
    return ParseInput("time,x,y,z\n0.0,0.5,-1.25,9.80665\n0.01,0.5,-1.25,9.80665\n", "log.csv",
                      read);
  });
  ASSERT_EQ(log.raw.samples.size(), 2u);
  EXPECT_EQ(log.raw.samples[1], Vec3(0.5, -1.25, 9.80665));
  EXPECT_EQ(log.raw.time_s[1], 0.01);

  std::vector<SystemSample> text_read;
  InCommaLocale([&] {
    ParseSeries("t,fx,fy,fz,roll,pitch\n0.5,1.25,-2.5e-3,9.81,0.001,0.002\n", "series.csv",
                [&](const SystemSample& s) { text_read.push_back(s); });
    return 0;
  });
  ASSERT_EQ(text_read.size(), 1u);
  EXPECT_EQ(text_read[0].t, 0.5);
  EXPECT_EQ(text_read[0].f, Vec3(1.25, -2.5e-3, 9.81));
  EXPECT_EQ(text_read[0].roll, 0.001);
  EXPECT_EQ(text_read[0].pitch, 0.002);

  // The series writer (binary) and its reader.
  SystemSample sample;
  sample.t = 0.1;
  sample.f = Vec3(0.2, -9.80665, 1e-300);
  sample.roll = 1.0 / 3.0;
  sample.pitch = -2.5e-7;
  const std::string bytes = InCommaLocale([&] {
    std::string out;
    AppendSeriesHeader(&out);
    AppendSeriesSample(sample, &out);
    return out;
  });
  std::vector<SystemSample> binary_read;
  InCommaLocale([&] {
    ParseSeries(bytes, "series.bin", [&](const SystemSample& s) { binary_read.push_back(s); });
    return 0;
  });
  ASSERT_EQ(binary_read.size(), 1u);
  EXPECT_EQ(binary_read[0].t, sample.t);
  EXPECT_EQ(binary_read[0].f, sample.f);
  EXPECT_EQ(binary_read[0].roll, sample.roll);
  EXPECT_EQ(binary_read[0].pitch, sample.pitch);
}

// The switch to the "C" locale is the calling thread's alone and undone after: the host's own
// printf keeps its decimal comma.
TEST_F(DecimalComma, TheHostKeepsItsLocale) {
  const std::string after = InCommaLocale([] {
    const Simulated s = Simulate();
    CalibrationToJson(s.result, s.info);  // Diagnose: printf in the "C" locale
    char buf[16];
    std::snprintf(buf, sizeof buf, "%.2f", 1.25);
    return std::string(buf) + " " + std::setlocale(LC_NUMERIC, nullptr);
  });
  EXPECT_EQ(after, std::string("1,25 ") + kCommaLocale);
}

}  // namespace
}  // namespace accelcal
