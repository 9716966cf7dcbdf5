// Exports to other tools' formats (export.hpp, docs/conventions.md): each read
// back the way its tool reads it and applied the way its tool applies it,
// against accelcal's own correction.
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/simulate.hpp"
#include "support/sample_noise.hpp"

namespace accelcal {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;

// A MEMS device in g (raw readings in g too, as a phone logs them, or in m/s2
// when `raw_unit` says so), fitted on 24 noisy positions.
struct Fitted {
  std::string json;
  LoadedCalibration cal;
};
Fitted Fit(ModelKind model, Frame frame, const std::string& raw_unit = "g",
           const std::string& source = "simulated") {
  ModelParameters truth;
  truth.K << 1.02, 0, 0, 0.01, 0.98, 0, -0.02, 0.015, 1.01;
  truth.bias << 0.03, -0.02, 0.05;
  if (model == ModelKind::kQuadratic) truth.k2 << 0.01, -0.008, 0.012;
  if (raw_unit == "m/s2") {  // readings in m/s2 of a force in g: K and b g0 times as large
    truth.K *= kStandardGravity_ms2;
    truth.bias *= kStandardGravity_ms2;
    truth.k2 *= kStandardGravity_ms2;
  }
  const std::vector<Vec3> readings =
      SimulatePositions(truth, 1.0, RandomDirectionsInCap(24, kPi, 3), Vec3::Constant(1e-3), 4);
  CalibrationOptions options;
  options.model = model;
  options.frame = frame;
  options.gravity = 1.0;
  const CalibrationResult result = Calibrate(readings, options);
  CalibrationFileInfo info;
  info.unit = ForceUnit::kStandardGravity;
  info.raw_unit = raw_unit;
  info.source = source;
  for (const Vec3& p : readings)
    info.positions.push_back(Position{p, 1, std::nullopt, std::nullopt, std::nullopt});
  Fitted fitted;
  fitted.json = CalibrationToJson(result, info);
  fitted.cal = ParseCalibrationJson(fitted.json, "cal.json");
  return fitted;
}

std::vector<double> Numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  return v;
}

// Every value of `NAME<sep>VALUE` lines whose name starts with `prefix`, in
// order.
std::vector<double> ParameterValues(const std::string& text, const std::string& prefix, char sep,
                                    int value_field) {
  std::vector<double> values;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> fields;
    std::stringstream fs_line(line);
    std::string field;
    while (std::getline(fs_line, field, sep)) fields.push_back(field);
    const std::string& name = fields[static_cast<std::size_t>(value_field - 1)];
    if (name.rfind(prefix, 0) == 0)
      values.push_back(std::stod(fields[static_cast<std::size_t>(value_field)]));
  }
  return values;
}

// The options' rules, stated once: values out of range, and an option given that the format has
// no use for (named as the field, marked for each edge to name its own way).
TEST(ExportOptions, ValidateRefusesValuesAndOptionsTheFormatDoesNotUse) {
  ExportOptions o;
  for (ExportFormat f : AllExportFormats()) EXPECT_EQ(o.Validate(f), std::nullopt) << ToString(f);
  EXPECT_EQ(o.Validate(ExportFormat::kPx4, {"c_prefix"}),
            "{{c_prefix}} is for c-header; px4 has no use for it");
  EXPECT_EQ(o.Validate(ExportFormat::kCHeader, {"c_prefix"}), std::nullopt);
  EXPECT_EQ(o.Validate(ExportFormat::kJson, {"rostopic"}),
            "{{rostopic}} is for kalibr-imu, kalibr and openvins; json has no use for it");
  o.instance = -1;
  EXPECT_EQ(o.Validate(ExportFormat::kPx4), "{{instance}} must be >= 0");
  o.instance = 4;
  EXPECT_TRUE(o.Validate(ExportFormat::kPx4));
  EXPECT_EQ(o.Validate(ExportFormat::kPx4, {}), o.Validate(ExportFormat::kPx4));
  o.instance = 3;
  EXPECT_EQ(o.Validate(ExportFormat::kPx4), std::nullopt);
  EXPECT_TRUE(o.Validate(ExportFormat::kArduPilot));
  o = ExportOptions{};
  o.c_prefix = "9lives";
  EXPECT_TRUE(o.Validate(ExportFormat::kCHeader));
  EXPECT_EQ(o.Validate(ExportFormat::kPx4), std::nullopt);  // not given: not used, not checked
  o = ExportOptions{};
  o.rostopic = "/imu//0";
  EXPECT_TRUE(o.Validate(ExportFormat::kKalibrImu));
  o = ExportOptions{};
  o.sensor = "gyroscope";
  EXPECT_TRUE(o.Validate(ExportFormat::kKalibr));
  EXPECT_EQ(o.Validate(ExportFormat::kImuTk), std::nullopt);
  o.gyro_raw_unit = "rpm";
  EXPECT_TRUE(o.Validate(ExportFormat::kImuTk));
}

TEST(Export, ImuTkAppliedAsImuTkDoesIsAccelcalsCorrection) {
  for (const Frame frame : {Frame::kXFirst, Frame::kZFirst}) {
    const Fitted f = Fit(ModelKind::kLinear, frame);
    const ExportResult e = ExportCalibration(f.cal, f.json, ExportFormat::kImuTk);
    // CalibratedTriad::load: 9 numbers of T (row-major), 9 of S, 3 of B; f = T
    // S (p − B).
    const std::vector<double> n = Numbers(e.text);
    ASSERT_EQ(n.size(), 21u);
    const Mat33 T = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(n.data());
    const Mat33 S = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(n.data() + 9);
    const Vec3 B(n[18], n[19], n[20]);
    EXPECT_EQ(T.diagonal(), Vec3::Ones());
    EXPECT_TRUE(S.isDiagonal(0));
    for (const Vec3& p : f.cal.position_means) {
      const Vec3 expected = *SpecificForce(f.cal.params, p);
      // K⁻¹ computed and split: a few roundings of a well-conditioned 3x3.
      EXPECT_LT((T * S * (p - B) - expected).norm(), 1e-14) << ToString(frame);
    }
    EXPECT_TRUE(e.loss.dropped.empty());
    EXPECT_LT(e.loss.max_error, 1e-14);
  }
}

TEST(Export, QuadraticTermsDroppedAreNamedAndMeasured) {
  const Fitted f = Fit(ModelKind::kQuadratic, Frame::kXFirst);
  const ExportResult e = ExportCalibration(f.cal, f.json, ExportFormat::kImuTk);
  EXPECT_EQ(e.loss.dropped, "the squared terms k2");
  // Independently: the linear part's correction against the full one on the
  // file's positions.
  double max_error = 0;
  for (const Vec3& p : f.cal.position_means) {
    const Vec3 linear = f.cal.params.K.inverse() * (p - f.cal.params.bias);
    max_error = std::max(max_error, (linear - *SpecificForce(f.cal.params, p)).norm());
  }
  EXPECT_EQ(e.loss.positions, 24);
  EXPECT_NEAR(e.loss.max_error, max_error, 1e-12);
  EXPECT_GT(e.loss.max_error, 5e-3);  // k2 ~ 0.01 per g²: a real loss, ~0.01 g
}

TEST(Export, Px4AndArduPilotHoldTheDiagonalAndSayWhatTheyDrop) {
  const Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
  const double g0 = kStandardGravity_ms2;
  for (const ExportFormat format : {ExportFormat::kPx4, ExportFormat::kArduPilot}) {
    const ExportResult e = ExportCalibration(f.cal, f.json, format);
    const bool px4 = format == ExportFormat::kPx4;
    // PX4: `1 1 CAL_ACC0_XOFF value 9` (tab-separated, offsets then scales);
    // ArduPilot: NAME,VALUE.
    const std::vector<double> offsets = px4 ? ParameterValues(e.text, "CAL_ACC0_", '\t', 3)
                                            : ParameterValues(e.text, "INS_ACCOFFS", ',', 1);
    const std::vector<double> scales = px4 ? std::vector<double>(offsets.begin() + 3, offsets.end())
                                           : ParameterValues(e.text, "INS_ACCSCAL", ',', 1);
    ASSERT_EQ(offsets.size(), px4 ? 6u : 3u);
    ASSERT_EQ(scales.size(), 3u);
    // The tool's correction (p − offset) .* scale on readings in m/s², here g
    // · 9.80665, gives m/s²; it equals (p − b)_i / K_ii in g, to the 9 digits
    // written.
    for (const Vec3& p : f.cal.position_means) {
      for (int i = 0; i < 3; ++i) {
        const auto j = static_cast<std::size_t>(i);
        const double tool = (g0 * p(i) - offsets[j]) * scales[j];
        const double expected = g0 * (p(i) - f.cal.params.bias(i)) / f.cal.params.K(i, i);
        EXPECT_NEAR(tool, expected, 1e-7) << ToString(format);
      }
    }
    EXPECT_EQ(e.loss.dropped, "the misalignments (K's off-diagonal terms)");
    // The dropped misalignments (0.01-0.02) move corrected readings by up to
    // ~2e-2 g.
    EXPECT_GT(e.loss.max_error, 1e-3);
    EXPECT_LT(e.loss.max_error, 5e-2);
  }
}

TEST(Export, ToolsThatNeedMetersPerSecond2RefuseOtherRawUnits) {
  const Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst, "counts");
  for (const ExportFormat format :
       {ExportFormat::kPx4, ExportFormat::kArduPilot, ExportFormat::kKalibr}) {
    try {
      ExportCalibration(f.cal, f.json, format);
      ADD_FAILURE() << ToString(format);
    } catch (const DataError& e) {
      EXPECT_NE(std::string(e.what()).find("this calibration's raw unit is 'counts'"),
                std::string::npos);
    }
  }
  ExportOptions said_g;
  said_g.raw_unit = "g";
  EXPECT_NO_THROW(ExportCalibration(f.cal, f.json, ExportFormat::kPx4, said_g));
}

// The targets that apply a calibration to readings in m/s2 and rates in rad/s
// load it as it is written, so each refuses, as the others do, a calibration no
// sensor has in those units. A Kalibr M of 4796 "in m/s2" (counts said to be
// m/s2) had been written, exit 0, where PX4 refused it.
const std::vector<ExportFormat> kPhysicalTargets = {ExportFormat::kPx4, ExportFormat::kArduPilot,
                                                    ExportFormat::kKalibr, ExportFormat::kOpenVins,
                                                    ExportFormat::kBasalt};

// The DataError of an export, or "" when it is written.
std::string Refusal(const Fitted& f, ExportFormat format, const ExportOptions& options) {
  try {
    ExportCalibration(f.cal, f.json, format, options);
    return "";
  } catch (const DataError& e) {
    return e.what();
  }
}

TEST(Export, EveryTargetInPhysicalUnitsRefusesScalesNoSensorHas) {
  ExportOptions options;
  options.noise = test::SampleNoise();
  const Fitted good = Fit(ModelKind::kLinear, Frame::kXFirst);
  for (const ExportFormat format : kPhysicalTargets) {
    EXPECT_EQ(Refusal(good, format, options), "") << ToString(format);
  }
  // Counts said to be g (a 4096-per-g part); K twice or a billionth of a
  // sensor's; an axis reading the negative of its force.
  const std::pair<const char*, Mat33> wrong[] = {
      {"counts", 4096 * good.cal.params.K},
      {"2x", 2 * good.cal.params.K},
      {"tiny", 1e-9 * good.cal.params.K},
      {"negative", Vec3(-1, 1, 1).asDiagonal() * good.cal.params.K}};
  for (const auto& [what, K] : wrong) {
    Fitted f = good;
    f.cal.params.K = K;
    for (const ExportFormat format : kPhysicalTargets) {
      const std::string refusal = Refusal(f, format, options);
      EXPECT_NE(refusal.find("would apply scales of"), std::string::npos)
          << what << " " << ToString(format) << ": " << refusal;
    }
  }
}

TEST(Export, EveryTargetInPhysicalUnitsRefusesOffsetsNoSensorHas) {
  // Datasheets' worst zero-g offsets are ~0.25 g: 0.45 g is a poor part's, 0.55
  // g and 500 m/s2 (51 g) no accelerometer's; the bound is 0.5 g, on every
  // axis.
  ExportOptions options;
  options.noise = test::SampleNoise();
  for (const auto& [offset_g, plausible] :
       {std::pair{0.45, true}, std::pair{-0.55, false}, std::pair{51.0, false}}) {
    for (int axis = 0; axis < 3; ++axis) {
      Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
      f.cal.params.bias(axis) = offset_g;
      for (const ExportFormat format : kPhysicalTargets) {
        const std::string refusal = Refusal(f, format, options);
        if (plausible) {
          EXPECT_EQ(refusal, "") << ToString(format);
        } else {
          EXPECT_NE(refusal.find("would apply offsets of"), std::string::npos)
              << offset_g << " " << ToString(format) << ": " << refusal;
        }
      }
    }
  }
}

TEST(Export, KalibrMIsKInTheXFirstFrameInMetersPerSecond2) {
  for (const Frame frame : {Frame::kXFirst, Frame::kZFirst}) {
    const Fitted f = Fit(ModelKind::kLinear, frame);
    const ExportResult e = ExportCalibration(f.cal, f.json, ExportFormat::kKalibr);
    // The three rows after "M:": a_measured = M a (+ b), lower-triangular.
    const std::string rows = e.text.substr(e.text.find("M:\n") + 3);
    std::string flat = rows.substr(0, rows.find("  #"));
    for (char& c : flat) {
      if (c == '[' || c == ']' || c == ',') c = ' ';
    }
    std::vector<double> n;
    std::istringstream in(flat);
    std::string token;
    while (in >> token) {
      if (token != "-") n.push_back(std::stod(token));  // "-" is the YAML list bullet
    }
    ASSERT_EQ(n.size(), 9u);
    const Mat33 M = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(n.data());
    EXPECT_EQ(M(0, 1), 0.0);
    EXPECT_EQ(M(0, 2), 0.0);
    EXPECT_EQ(M(1, 2), 0.0);
    // Readings and bias in m/s² (raw g · g0); the corrected magnitude is the
    // frame-free check.
    const double g0 = kStandardGravity_ms2;
    for (const Vec3& p : f.cal.position_means) {
      const Vec3 a = M.inverse() * (g0 * (p - f.cal.params.bias));
      EXPECT_NEAR(a.norm(), g0 * SpecificForce(f.cal.params, p)->norm(), 1e-12);
    }
    EXPECT_TRUE(e.loss.dropped.empty());
  }
}

int Shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(Export, CHeaderCompiledAndRunGivesAccelcalsCorrectionBitForBit) {
  const fs::path dir = fs::path(::testing::TempDir()) / "accelcal_c_header";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const auto& [model, frame] : {std::pair{ModelKind::kLinear, Frame::kXFirst},
                                     std::pair{ModelKind::kQuadratic, Frame::kXFirst},
                                     std::pair{ModelKind::kQuadratic, Frame::kZFirst}}) {
    const Fitted f = Fit(model, frame);
    ExportOptions options;
    options.c_prefix = "imu0";
    std::ofstream((dir / "cal.h").string())
        << ExportCalibration(f.cal, f.json, ExportFormat::kCHeader, options).text;
    std::ofstream((dir / "main.c").string())
        << "#include <stdio.h>\n#include \"cal.h\"\nint main(void) {\n  double "
           "p[3], f[3];\n"
           "  while (scanf(\"%lf %lf %lf\", &p[0], &p[1], &p[2]) == 3) {\n"
           "    if (imu0_correct(p, f) != 0) return 2;\n"
           "    printf(\"%.17g %.17g %.17g\\n\", f[0], f[1], f[2]);\n  }\n  "
           "return 0;\n}\n";
    std::ofstream in((dir / "in.txt").string());
    in.precision(17);
    for (const Vec3& p : f.cal.position_means) in << p(0) << " " << p(1) << " " << p(2) << "\n";
    in.close();
    // -ffp-contract=off: no fused multiply-add, as the library is compiled.
    ASSERT_EQ(Shell("cc -std=c99 -pedantic -Wall -Werror -O2 -ffp-contract=off -o " +
                    (dir / "app").string() + " " + (dir / "main.c").string() + " -lm"),
              0);
    ASSERT_EQ(Shell((dir / "app").string() + " < " + (dir / "in.txt").string() + " > " +
                    (dir / "out.txt").string()),
              0);
    std::ifstream out((dir / "out.txt").string());
    std::vector<double> n = Numbers(std::string(std::istreambuf_iterator<char>(out), {}));
    ASSERT_EQ(n.size(), 3 * f.cal.position_means.size());
    for (std::size_t k = 0; k < f.cal.position_means.size(); ++k) {
      const Vec3 expected = *SpecificForce(f.cal.params, f.cal.position_means[k]);
      for (int i = 0; i < 3; ++i)
        EXPECT_EQ(n[3 * k + static_cast<std::size_t>(i)], expected(i)) << k;
    }
  }
}

// A gyroscope beside the accelerometer of Fit (its numbers as the Xsens
// recording's).
UnitGyroscope Gyroscope() {
  UnitGyroscope g;
  g.model = GyroModelKind::kGSensitive;
  g.params.K << 4782.3, -42.2, -53.7, -25.7, 4765.3, 151.1, -75.1, 108.3, 4768.8;
  g.params.bias << 32770.3, 32451.1, 32509.4;
  g.params.G << 0.083, 0.305, 0.663, -1.346, 0.043, 0.841, -0.733, -0.801, 0.247;
  g.raw_unit = "counts";
  return g;
}

// The same gyroscope behind a driver that scales its rates to `unit`
// (`per_rad_s` of them a rad/s): the counts taken from their zero (32768) and
// divided by the nominal 4780 per rad/s.
UnitGyroscope ScaledGyroscope(const std::string& unit, double per_rad_s) {
  UnitGyroscope g = Gyroscope();
  const double s = per_rad_s / 4780;
  g.params.K *= s;
  g.params.bias = s * (g.params.bias - Vec3::Constant(32768));
  g.params.G *= s;
  g.raw_unit = unit;
  return g;
}

// The three rows "- [a, b, c]" after the line `key` at or after `from` in a
// YAML text.
Mat33 YamlRows(const std::string& text, const std::string& from, const std::string& key) {
  std::size_t at = text.find(from);
  at = text.find(key + "\n", at);
  EXPECT_NE(at, std::string::npos) << key;
  std::istringstream in(text.substr(at + key.size() + 1));
  Mat33 M;
  for (int i = 0; i < 3; ++i) {
    std::string line;
    std::getline(in, line);
    for (char& c : line) {
      if (c == '[' || c == ']' || c == ',') c = ' ';
    }
    std::istringstream row(line.substr(line.find('-') + 1));  // after the list's bullet
    for (int j = 0; j < 3; ++j) row >> M(i, j);
  }
  return M;
}

TEST(Export, KalibrGyroscopeAppliedAsKalibrDoesIsAccelcalsModel) {
  // Kalibr's reference IMU: w_measured = M C_gyro_i w + A C_gyro_i a + b in
  // rad/s, for w and a in the IMU frame of its accelerometer's M (accelcal's
  // x-first frame). Read back and applied to rates and forces in that frame, it
  // gives accelcal's K_g w + b_g + G f (times the rad/s of a raw unit) for the
  // same vectors in the calibration's own frame, to round-off.
  for (const Frame frame : {Frame::kXFirst, Frame::kZFirst}) {
    Fitted f = Fit(ModelKind::kLinear, frame);
    f.cal.gyroscope = ScaledGyroscope("raw", 180 / kPi);
    ExportOptions options;
    options.gyro_raw_unit = "deg/s";  // the rates said to be in deg/s: s = π/180
    const ExportResult e = ExportCalibration(f.cal, f.json, ExportFormat::kKalibr, options);
    EXPECT_TRUE(e.gyroscope_included);
    EXPECT_TRUE(e.loss.dropped.empty());
    const Mat33 M = YamlRows(e.text, "gyroscopes:", "    M:");
    const Mat33 A = YamlRows(e.text, "gyroscopes:", "    A:");
    const Mat33 C = YamlRows(e.text, "gyroscopes:", "    C_gyro_i:");
    EXPECT_EQ(M(0, 1), 0.0);
    EXPECT_EQ(M(0, 2), 0.0);
    EXPECT_EQ(M(1, 2), 0.0);
    EXPECT_LT((C * C.transpose() - Mat33::Identity()).norm(), 1e-15);
    EXPECT_NEAR(C.determinant(), 1.0, 1e-15);
    const Mat33 Q = ChangeFrame(f.cal.params.K, Frame::kXFirst).Q_old_new;
    const double s = kPi / 180,
                 g0 = kStandardGravity_ms2;  // the calibration's force unit is g
    const GyroParameters& g = f.cal.gyroscope->params;
    for (const auto& [w, a] : {std::pair<Vec3, Vec3>{{0.3, -1.2, 0.7}, {1.0, -9.0, 3.5}},
                               std::pair<Vec3, Vec3>{{-2.0, 0.1, 0.4}, {9.8, 0.2, -0.3}}}) {
      const Vec3 kalibr = M * C * w + A * C * a;
      const Vec3 accelcal = s * (g.K * (Q * w) + g.G * (Q * a / g0));
      EXPECT_LT((kalibr - accelcal).norm(), 1e-12 * accelcal.norm()) << ToString(frame);
    }
  }
  // Rates in counts are left out, saying why and which option says otherwise.
  Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
  f.cal.gyroscope = Gyroscope();
  const ExportResult e = ExportCalibration(f.cal, f.json, ExportFormat::kKalibr);
  EXPECT_FALSE(e.gyroscope_included);
  EXPECT_EQ(e.text.find("gyroscopes:"), std::string::npos);
  EXPECT_NE(e.gyroscope_omitted.find("gyro_raw_unit"), std::string::npos) << e.gyroscope_omitted;
}

TEST(Export, GyroscopesNoSensorHasAreLeftOutOrRefused) {
  // Kalibr and PX4 hold a gyroscope beside the accelerometer: one no sensor has
  // is left out, saying why; OpenVINS' and Basalt's files state one in any
  // case, so they refuse the export.
  ExportOptions options;
  options.noise = test::SampleNoise();
  Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
  f.cal.gyroscope = ScaledGyroscope("rad/s", 1);
  for (const ExportFormat format : {ExportFormat::kPx4, ExportFormat::kKalibr,
                                    ExportFormat::kOpenVins, ExportFormat::kBasalt}) {
    EXPECT_TRUE(ExportCalibration(f.cal, f.json, format, options).gyroscope_included)
        << ToString(format);
  }
  // A gyroscope turned 90 degrees from the accelerometer is a sensor's: the
  // estimators hold the rotation between them (Kalibr's C_gyro_i), so its
  // scales are 1.
  Fitted turned = f;
  turned.cal.gyroscope->params.K =
      f.cal.gyroscope->params.K * Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ()).toRotationMatrix();
  for (const ExportFormat format :
       {ExportFormat::kKalibr, ExportFormat::kOpenVins, ExportFormat::kBasalt}) {
    EXPECT_TRUE(ExportCalibration(turned.cal, turned.json, format, options).gyroscope_included)
        << ToString(format);
  }
  // Rates in deg/s said to be rad/s; offsets of 3 rad/s (172 deg/s, beyond any
  // gyroscope's).
  Fitted degrees = f;
  degrees.cal.gyroscope = ScaledGyroscope("rad/s", 180 / kPi);
  Fitted offset = f;
  offset.cal.gyroscope->params.bias(1) = 3;
  for (const auto& [wrong, why] : {std::pair{&degrees, "would apply gyroscope scales"},
                                   std::pair{&offset, "would apply gyroscope offsets"}}) {
    const ExportResult kalibr =
        ExportCalibration(wrong->cal, wrong->json, ExportFormat::kKalibr, options);
    EXPECT_FALSE(kalibr.gyroscope_included);
    EXPECT_EQ(kalibr.text.find("gyroscopes:"), std::string::npos);
    EXPECT_NE(kalibr.gyroscope_omitted.find(why), std::string::npos) << kalibr.gyroscope_omitted;
    EXPECT_FALSE(
        ExportCalibration(wrong->cal, wrong->json, ExportFormat::kPx4, options).gyroscope_included);
    for (const ExportFormat format : {ExportFormat::kOpenVins, ExportFormat::kBasalt}) {
      const std::string refusal = Refusal(*wrong, format, options);
      EXPECT_NE(refusal.find(why), std::string::npos) << ToString(format) << ": " << refusal;
    }
  }
  const ExportResult px4 = ExportCalibration(offset.cal, offset.json, ExportFormat::kPx4, options);
  EXPECT_EQ(px4.text.find("CAL_GYRO"), std::string::npos) << px4.text;
  EXPECT_NE(px4.gyroscope_omitted.find("would apply gyroscope offsets"), std::string::npos)
      << px4.gyroscope_omitted;
}

TEST(Export, ImuTkGyroscopeAppliedAsImuTkDoesIsAccelcalsCorrectionLessG) {
  Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
  f.cal.gyroscope = Gyroscope();
  ExportOptions options;
  options.sensor = "gyroscope";
  const ExportResult e = ExportCalibration(f.cal, f.json, ExportFormat::kImuTk, options);
  EXPECT_TRUE(e.gyroscope_included);
  const std::vector<double> n = Numbers(e.text);
  ASSERT_EQ(n.size(), 21u);
  const Mat33 T = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(n.data());
  const Mat33 S = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(n.data() + 9);
  const Vec3 B(n[18], n[19], n[20]);
  EXPECT_EQ(T.diagonal(), Vec3::Ones());
  EXPECT_TRUE(S.isDiagonal(0));
  const GyroParameters& g = f.cal.gyroscope->params;
  for (const Vec3& raw : {Vec3(32770, 32451, 32509), Vec3(40000, 30000, 20000)}) {
    const Vec3 expected = g.K.inverse() * (raw - g.bias);  // G f dropped
    EXPECT_LT((T * S * (raw - B) - expected).norm(), 1e-15 * (1 + expected.norm()));
  }
  // What it drops: |K⁻¹ G f| at |f| = g at its largest, in °/h.
  const double largest = Eigen::JacobiSVD<Mat33>(Mat33(g.K.inverse() * g.G)).singularValues()(0);
  char expected[64];
  std::snprintf(expected, sizeof expected, "up to %.3g deg/h",
                largest * f.cal.gravity * 180 / kPi * 3600);
  EXPECT_NE(e.gyroscope_dropped.find(expected), std::string::npos) << e.gyroscope_dropped;
  // Without a gyroscope in the file, or for another format, the sensor is
  // refused.
  EXPECT_THROW(ExportCalibration(Fit(ModelKind::kLinear, Frame::kXFirst).cal, f.json,
                                 ExportFormat::kImuTk, options),
               DataError);
  EXPECT_THROW(ExportCalibration(f.cal, f.json, ExportFormat::kKalibr, options),
               std::invalid_argument);
}

TEST(Export, CHeaderCorrectsTheGyroscopeBitForBit) {
  const fs::path dir = fs::path(::testing::TempDir()) / "accelcal_c_header_gyro";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
  f.cal.gyroscope = Gyroscope();
  const ExportResult e = ExportCalibration(f.cal, f.json, ExportFormat::kCHeader);
  EXPECT_TRUE(e.gyroscope_included);
  std::ofstream((dir / "cal.h").string()) << e.text;
  std::ofstream((dir / "main.c").string())
      << "#include <stdio.h>\n#include \"cal.h\"\nint main(void) {\n  double "
         "raw[3], f[3], w[3];\n"
         "  while (scanf(\"%lf %lf %lf %lf %lf %lf\", &raw[0], &raw[1], "
         "&raw[2], &f[0], &f[1], "
         "&f[2]) == 6) {\n    accelcal_correct_gyro(raw, f, w);\n"
         "    printf(\"%.17g %.17g %.17g\\n\", w[0], w[1], w[2]);\n  }\n  "
         "return 0;\n}\n";
  const std::vector<std::pair<Vec3, Vec3>> samples = {
      {Vec3(32770, 32451, 32509), Vec3(0, 0, 9.81)},
      {Vec3(40000.5, 30000.25, 20000.125), Vec3(3.1, -4.2, 8.0)}};
  std::ofstream in((dir / "in.txt").string());
  in.precision(17);
  for (const auto& [raw, force] : samples) {
    in << raw(0) << " " << raw(1) << " " << raw(2) << " " << force(0) << " " << force(1) << " "
       << force(2) << "\n";
  }
  in.close();
  ASSERT_EQ(Shell("cc -std=c99 -pedantic -Wall -Werror -O2 -ffp-contract=off -o " +
                  (dir / "app").string() + " " + (dir / "main.c").string() + " -lm"),
            0);
  ASSERT_EQ(Shell((dir / "app").string() + " < " + (dir / "in.txt").string() + " > " +
                  (dir / "out.txt").string()),
            0);
  std::ifstream out((dir / "out.txt").string());
  const std::vector<double> n = Numbers(std::string(std::istreambuf_iterator<char>(out), {}));
  ASSERT_EQ(n.size(), 6u);
  // The header's constants are the printed doubles of K_g⁻¹, b and G: the same
  // operations in the same order here give the same bits.
  const GyroParameters& g = f.cal.gyroscope->params;
  const Mat33 K_inverse = g.K.inverse();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const auto& [raw, force] = samples[k];
    double r[3];
    for (int i = 0; i < 3; ++i) {
      r[i] =
          raw(i) - g.bias(i) - g.G(i, 0) * force(0) - g.G(i, 1) * force(1) - g.G(i, 2) * force(2);
    }
    for (int i = 0; i < 3; ++i) {
      const double w = K_inverse(i, 0) * r[0] + K_inverse(i, 1) * r[1] + K_inverse(i, 2) * r[2];
      EXPECT_EQ(n[3 * k + static_cast<std::size_t>(i)], w) << k << " " << i;
    }
  }
}

TEST(Export, YamlReadsBackAsTheSameDocumentInAYaml11Reader) {
  // PyYAML (YAML 1.1, Debian's python3-yaml) is the strictest common reader: it
  // takes 1e-05 for a string. The document must compare equal to the JSON one,
  // every number exactly.
  const fs::path dir = fs::path(::testing::TempDir()) / "accelcal_yaml";
  fs::create_directories(dir);
  const Fitted f = Fit(ModelKind::kQuadratic, Frame::kZFirst);
  std::ofstream((dir / "cal.json").string()) << f.json;
  std::ofstream((dir / "cal.yaml").string())
      << ExportCalibration(f.cal, f.json, ExportFormat::kYaml).text;
  EXPECT_NE(f.json.find("e-"),
            std::string::npos);  // small numbers in exponent form are in it
  EXPECT_EQ(Shell("/usr/bin/python3 -c \"import json, sys, yaml; "
                  "sys.exit(json.load(open(sys.argv[1])) != "
                  "yaml.safe_load(open(sys.argv[2])))\" " +
                  (dir / "cal.json").string() + " " + (dir / "cal.yaml").string()),
            0);
  EXPECT_EQ(ExportCalibration(f.cal, f.json, ExportFormat::kJson).text, f.json);
}

// Labels and paths as hostile as a command line allows (no NUL): the C
// comment's terminator and opener, the ??/ trigraph (a backslash in C99), line
// breaks of every kind (LF, CR, VT, FF, NEL, U+2028, U+2029), parameter lines
// of each tool after them, other control characters, quotes, YAML indicators,
// non-ASCII letters and an emoji, and a backslash at the end.
const std::string kEvilUnit =
    "counts */ int evil2 = 2; "
    "/*\nINS_EVIL,1\r1\t1\tCAL_EVIL\t1\t9\x0b\x0c\x1b[31m\x7f \"q\" 'q' : "
    "# ?\?/ \xc2\x85NEL \xe2\x80\xa8LS \xe2\x80\xa9PS \xc3\xa4 "
    "\xf0\x9f\x98\x80 \\";
const std::string kEvilSource =
    "/logs/*/x.csv\nimu1:\n  model: "
    "evil\r\nINS_ACCSCAL_X,7\n1\t1\tCAL_ACC0_XOFF\t7\t9\n# "
    "*/ int evil = 1; /* \"a\" 'b': c #d \x01\x1f \xc3\xa9t\xc3\xa9 ?\?\?/";

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// The lines that are no comment (not starting with `comment`), in order.
std::vector<std::string> Content(const std::string& text, const std::string& comment) {
  std::vector<std::string> out;
  for (const std::string& line : Lines(text)) {
    if (line.rfind(comment, 0) != 0) out.push_back(line);
  }
  return out;
}

// No control character but tab and line feed, and no line separator of YAML 1.1
// or Python's splitlines (NEL, U+2028, U+2029).
void ExpectOnlyPlainLines(const std::string& text, const std::string& what) {
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    EXPECT_FALSE((u < 0x20 && c != '\t' && c != '\n') || u == 0x7f)
        << what << ": control character " << static_cast<int>(u);
  }
  for (const char* separator : {"\xc2\x85", "\xe2\x80\xa8", "\xe2\x80\xa9"}) {
    EXPECT_EQ(text.find(separator), std::string::npos) << what;
  }
}

std::string Slurp(const fs::path& path) {
  std::ifstream in(path.string());
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(Export, LabelsAndPathsChangeNoFileBeyondItsComments) {
  const Fitted evil = Fit(ModelKind::kLinear, Frame::kXFirst, kEvilUnit, kEvilSource);
  const Fitted clean = Fit(ModelKind::kLinear, Frame::kXFirst, "g", "simulated");
  ASSERT_EQ(evil.cal.raw_unit,
            kEvilUnit);  // the calibration file holds them exactly
  ASSERT_EQ(evil.cal.source, kEvilSource);
  ASSERT_EQ(evil.cal.params.K, clean.cal.params.K);
  ExportOptions g;
  g.raw_unit = "g";  // what the readings were: the label is no unit PX4 or
                     // ArduPilot knows
  const auto both = [&](ExportFormat format) {
    return std::pair(ExportCalibration(evil.cal, evil.json, format, g),
                     ExportCalibration(clean.cal, clean.json, format, g));
  };

  // PX4 and ArduPilot: the same parameter lines, byte for byte, as many comment
  // lines.
  for (const ExportFormat format : {ExportFormat::kPx4, ExportFormat::kArduPilot}) {
    const auto [e, c] = both(format);
    EXPECT_EQ(Content(e.text, "#"), Content(c.text, "#")) << e.text;
    EXPECT_EQ(Content(e.text, "#").size(), 6u);
    EXPECT_EQ(Lines(e.text).size(), Lines(c.text).size()) << e.text;
    ExpectOnlyPlainLines(e.text, std::string(ToString(format)));
    ExpectOnlyPlainLines(e.convention, "convention");
    // The labels are there, visibly: the path's line break as \n.
    EXPECT_NE(e.text.find("/logs/*/x.csv\\nimu1:\\n  model: evil\\r\\nINS_ACCSCAL_X,7"),
              std::string::npos)
        << e.text;
    EXPECT_NE(e.text.find("raw 'counts */ int evil2 = 2; /*\\nINS_EVIL,1\\r1\\t1"),
              std::string::npos)
        << e.text;
  }

  // Kalibr: the same YAML lines, and PyYAML reads the same document from both.
  const fs::path dir = fs::path(::testing::TempDir()) / "accelcal_evil_labels";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    const auto [e, c] = both(ExportFormat::kKalibr);
    EXPECT_EQ(Content(e.text, "#"), Content(c.text, "#"));
    EXPECT_EQ(Lines(e.text).size(), Lines(c.text).size()) << e.text;
    ExpectOnlyPlainLines(e.text, "kalibr");
    std::ofstream((dir / "evil.yaml").string()) << e.text;
    std::ofstream((dir / "clean.yaml").string()) << c.text;
    EXPECT_EQ(Shell("/usr/bin/python3 -c \"import sys, yaml; "
                    "sys.exit(yaml.safe_load(open(sys.argv[1], encoding='utf-8')) != "
                    "yaml.safe_load(open(sys.argv[2], encoding='utf-8')))\" " +
                    (dir / "evil.yaml").string() + " " + (dir / "clean.yaml").string()),
              0);
  }

  // imu_tk holds no label: the same bytes.
  EXPECT_EQ(both(ExportFormat::kImuTk).first.text, both(ExportFormat::kImuTk).second.text);

  // C header: compiles warning-free as C99 (trigraphs on: ??/ is a backslash;
  // -Wcomment: no /* in a comment), and after the preprocessor (comments gone)
  // is the clean header's code.
  const auto [e, c] = both(ExportFormat::kCHeader);
  ExpectOnlyPlainLines(e.text, "c-header");
  EXPECT_EQ(Lines(e.text).size(), Lines(c.text).size()) << e.text;
  // The first comment ends where the clean header's does: at the end of its
  // third line.
  EXPECT_EQ(e.text.find("*/"), e.text.find(" */\n#ifndef") + 1) << e.text;
  EXPECT_EQ(Lines(e.text.substr(0, e.text.find("*/"))).size(), 3u) << e.text;
  std::ofstream((dir / "evil.h").string()) << e.text;
  std::ofstream((dir / "clean.h").string()) << c.text;
  ASSERT_EQ(Shell("cc -std=c99 -pedantic -Wall -Wextra -Werror -fsyntax-only -x c " +
                  (dir / "evil.h").string()),
            0)
      << e.text;
  ASSERT_EQ(Shell("cc -std=c99 -E -P -x c " + (dir / "evil.h").string() + " -o " +
                  (dir / "evil.i").string()),
            0);
  ASSERT_EQ(Shell("cc -std=c99 -E -P -x c " + (dir / "clean.h").string() + " -o " +
                  (dir / "clean.i").string()),
            0);
  EXPECT_EQ(Slurp(dir / "evil.i"), Slurp(dir / "clean.i"));
}

TEST(Export, LabelsThatAreNoUtf8AreWrittenWithTheReplacementCharacter) {
  // A Latin-1 file name and label: JSON holds no such bytes, so the file has
  // U+FFFD for each.
  const Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst, "z\xe4hler", "/logs/m\xfcll.csv");
  EXPECT_EQ(f.cal.raw_unit, "z\xef\xbf\xbdhler");
  EXPECT_EQ(f.cal.source, "/logs/m\xef\xbf\xbdll.csv");
  for (const ExportFormat format : AllExportFormats()) {
    ExportOptions g;
    g.raw_unit = "g";
    g.noise = test::SampleNoise("/logs/r\xe4uschen.json");  // the noise formats' comments too
    EXPECT_NE(ExportCalibration(f.cal, f.json, format, g).text, "") << ToString(format);
  }
}

TEST(Export, YamlHoldsEveryStringExactly) {
  // The whole calibration document with the labels, and keys no YAML 1.1 reader
  // may take for booleans or null, read by PyYAML: equal to the JSON, every
  // string exact.
  const fs::path dir = fs::path(::testing::TempDir()) / "accelcal_yaml_strings";
  fs::create_directories(dir);
  const Fitted f = Fit(ModelKind::kQuadratic, Frame::kZFirst, kEvilUnit, kEvilSource);
  const std::string keys =
      R"({"on": "off", "y": "n", "No": null, "key with space": "yes", "a\u2028b": "\u0085\u007f",
          "\ufeff": ["\ud83d\ude00", "\u0000x\u0001", "# not a comment", "- not a list"]})";
  int i = 0;
  for (const std::string& json : {f.json, keys}) {
    const std::string name = "doc" + std::to_string(i++);
    std::ofstream((dir / (name + ".json")).string()) << json;
    const std::string yaml = JsonToYaml(json);
    std::ofstream((dir / (name + ".yaml")).string()) << yaml;
    ExpectOnlyPlainLines(yaml, name);
    EXPECT_EQ(Shell("/usr/bin/python3 -c \"import json, sys, yaml; "
                    "sys.exit(json.load(open(sys.argv[1], encoding='utf-8')) != "
                    "yaml.safe_load(open(sys.argv[2], encoding='utf-8')))\" " +
                    (dir / (name + ".json")).string() + " " + (dir / (name + ".yaml")).string()),
              0)
        << yaml;
  }
  // Plain keys stay plain (the file reads as before).
  EXPECT_EQ(JsonToYaml(R"({"format": "accelcal", "K": [1.0, 2.5e-05]})"),
            "%YAML 1.2\n---\nformat: \"accelcal\"\nK: [1.0, 2.5e-05]\n");
}

TEST(Export, VisibleLineEscapesWhatWouldBreakALine) {
  EXPECT_EQ(VisibleLine("a\nb\rc\td"), "a\\nb\\rc\\td");
  EXPECT_EQ(VisibleLine(std::string("\x01\x1b\x7f", 3)), "\\x01\\x1B\\x7F");
  EXPECT_EQ(VisibleLine("\xc2\x85\xc2\x9f\xe2\x80\xa8\xe2\x80\xa9\xef\xbb\xbf\xef\xbf\xbf"),
            "\\x85\\x9F\\u2028\\u2029\\uFEFF\\uFFFF");
  // The bidirectional controls, which reorder what a terminal shows after them
  // (issue 47: a topic named with U+202E in inspect's listing and the PX4
  // export's comment): U+061C, U+200E, U+200F, U+202A to U+202E, U+2066 to
  // U+2069; their neighbours U+202F, U+2065, U+206A kept.
  EXPECT_EQ(VisibleLine("a\xe2\x80\xae"
                        "b\xd8\x9c\xe2\x80\x8e\xe2\x80\x8f\xe2\x80\xaa\xe2\x81"
                        "\xa6\xe2\x81\xa9"),
            "a\\u202Eb\\u061C\\u200E\\u200F\\u202A\\u2066\\u2069");
  const std::string neighbours = "\xe2\x80\xaf\xe2\x81\xa5\xe2\x81\xaa\xe2\x80\x8d";
  EXPECT_EQ(VisibleLine(neighbours), neighbours);
  // Bytes that are no UTF-8: a lone continuation, a truncated sequence, an
  // overlong '/', a surrogate.
  EXPECT_EQ(VisibleLine("\x80 \xe2\x80 \xc0\xaf \xed\xa0\x80"),
            "\\x80 \\xE2\\x80 \\xC0\\xAF \\xED\\xA0\\x80");
  // Printable text is kept as it is: quotes, backslashes, comment markers,
  // Unicode.
  const std::string printable = "C:\\logs\\\"a\" 'b' */ # \xc3\xa4\xc2\xa0\xf0\x9f\x98\x80";
  EXPECT_EQ(VisibleLine(printable), printable);
}

TEST(Export, NeverWritesANumberThatIsNot) {
  // Parameters at the edge of double arithmetic: every format either writes
  // numbers alone or refuses (DataError). A K of 1e160 had gone through QR and
  // inversions to "null" in OpenVINS' Tw and Ta with exit 0, and 1e-200 to
  // nulls in Basalt's calib_accel_bias.
  for (const double extreme : {1e160, 1e-200, 1e-310, 1e300}) {
    Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
    f.cal.params.K(0, 0) = extreme;
    f.cal.gyroscope = Gyroscope();
    f.cal.gyroscope->raw_unit = "rad/s";
    f.cal.gyroscope->params.K(1, 1) = extreme;
    ExportOptions options;
    options.noise = test::SampleNoise();
    for (const ExportFormat format : AllExportFormats()) {
      if (format == ExportFormat::kJson || format == ExportFormat::kYaml) continue;  // the file
      try {
        const std::string text = ExportCalibration(f.cal, f.json, format, options).text;
        for (const char* bad : {"null", "inf", "nan", "NaN", "Inf"}) {
          EXPECT_EQ(text.find(bad), std::string::npos)
              << ToString(format) << " at " << extreme << ":\n"
              << text;
        }
      } catch (const DataError& e) {
        // Not finite; beyond a float32 parameter (PX4, ArduPilot); or scales no
        // sensor has.
        const std::string what = e.what();
        EXPECT_TRUE(what.find("not finite") != std::string::npos ||
                    what.find("beyond a float32 parameter's range") != std::string::npos ||
                    what.find("would apply scales of") != std::string::npos ||
                    what.find("would apply gyroscope scales") != std::string::npos)
            << what;
      }
    }
  }
}

TEST(Export, UnitOverridesMayNotContradictTheFile) {
  // --raw-unit and --gyro-raw-unit name a unit the file does not say ("raw",
  // "counts"); against one it says they would scale everything by 9.81 or 57.3
  // without a word.
  Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst, "m/s2");
  f.cal.gyroscope = ScaledGyroscope("deg/s", 180 / kPi);
  ExportOptions g;
  g.raw_unit = "g";
  EXPECT_THROW(ExportCalibration(f.cal, f.json, ExportFormat::kPx4, g), std::invalid_argument);
  ExportOptions rad;
  rad.gyro_raw_unit = "rad/s";
  EXPECT_THROW(ExportCalibration(f.cal, f.json, ExportFormat::kKalibr, rad), std::invalid_argument);
  rad.gyro_raw_unit = "furlong/s";  // not a unit the gyroscope's formats read
  EXPECT_THROW(ExportCalibration(f.cal, f.json, ExportFormat::kKalibr, rad), std::invalid_argument);
  ExportOptions same;  // the file's own units, said again: fine
  same.raw_unit = "m/s2";
  same.gyro_raw_unit = "deg/s";
  EXPECT_TRUE(ExportCalibration(f.cal, f.json, ExportFormat::kKalibr, same).gyroscope_included);
  // OpenVINS and Basalt state the gyroscope's model in any case: one they
  // cannot convert is refused, not written as the identity.
  f.cal.gyroscope->raw_unit = "raw";
  ExportOptions noise;
  noise.noise = test::SampleNoise();
  for (const ExportFormat format : {ExportFormat::kOpenVins, ExportFormat::kBasalt}) {
    EXPECT_THROW(ExportCalibration(f.cal, f.json, format, noise), DataError) << ToString(format);
  }
}

TEST(Export, TopicsAreRosNames) {
  const Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst);
  ExportOptions o;
  o.noise = test::SampleNoise();
  for (const char* good : {"/imu0", "imu", "~/imu", "/a_b/c1", "_hidden/imu"}) {
    o.rostopic = good;
    EXPECT_NO_THROW(ExportCalibration(f.cal, f.json, ExportFormat::kOpenVins, o)) << good;
  }
  for (const char* bad : {"", "/", "//imu", "/imu0/", "/0imu", "a b", "~imu", "/imu/~", "/ä"}) {
    o.rostopic = bad;
    EXPECT_THROW(ExportCalibration(f.cal, f.json, ExportFormat::kOpenVins, o),
                 std::invalid_argument)
        << bad;
  }
}

TEST(Export, YamlNumbersAreNumbersToYaml11) {
  // PyYAML (Kalibr's reader) takes 5e-05 for a string: YAML 1.1's floats need a
  // '.' in the mantissa. Every number of the YAML formats is read back as a
  // float.
  const fs::path dir = fs::path(::testing::TempDir()) / "accelcal_yaml_numbers";
  fs::create_directories(dir);
  Fitted f = Fit(ModelKind::kLinear, Frame::kXFirst, "m/s2");
  f.cal.gyroscope = ScaledGyroscope("rad/s", 1);
  ExportOptions o;
  o.noise = test::SampleNoise();
  o.noise->accelerometer.white = Vec3::Constant(5e-05);
  o.noise->gyroscope->random_walk = Vec3::Constant(1e+300);
  o.noise->rate_hz = 200;
  for (const ExportFormat format : {ExportFormat::kKalibr, ExportFormat::kKalibrImu,
                                    ExportFormat::kRos, ExportFormat::kOpenVins}) {
    std::string text = ExportCalibration(f.cal, f.json, format, o).text;
    if (text.rfind("%YAML:1.0\n", 0) == 0) text.erase(0, 10);  // OpenCV's directive
    const fs::path file = dir / (std::string(ToString(format)) + ".yaml");
    std::ofstream(file.string()) << text;
    // Every scalar but the topic and the model's name is a float.
    EXPECT_EQ(Shell("/usr/bin/python3 -c \"import sys, yaml\n"
                    "def walk(x, key=''):\n"
                    "    if isinstance(x, dict): [walk(v, k) for k, v in x.items()]\n"
                    "    elif isinstance(x, list): [walk(v, key) for v in x]\n"
                    "    elif key not in ('rostopic', 'model'):\n"
                    "        assert isinstance(x, float), (key, x)\n"
                    "walk(yaml.safe_load(open(sys.argv[1])))\" " +
                    file.string()),
              0)
        << text;
  }
}

TEST(Export, FormatNamesRoundTrip) {
  for (const ExportFormat format : AllExportFormats()) {
    EXPECT_EQ(ExportFormatFromString(ToString(format)), format);
  }
  EXPECT_FALSE(ExportFormatFromString("csv").has_value());
}

}  // namespace
}  // namespace accelcal
