// The HTML report (report.hpp): its structure, checked without a browser, and its warnings. The
// page as a person sees it is checked in headless Chromium by tests/report_browser_test.sh.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/report.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::size_t Count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// A simulated recording of a MEMS device in g, detected and calibrated as the CLI does.
struct Recording {
  RawLog log;
  StaticDetectionResult detection;
  std::string json;
  LoadedCalibration cal;  // the file, read
};
Recording Record(const std::vector<Vec3>& directions, ModelKind model, double static_s = 4.0,
                 int moved = -1, OutlierPolicy outliers = OutlierPolicy::kExclude) {
  ModelParameters truth;
  truth.K << 1.02, 0, 0, 0.01, 0.98, 0, -0.02, 0.015, 1.01;
  truth.bias << 0.03, -0.02, 0.05;
  RawLogSimulation sim;
  sim.rate_hz = 100;
  sim.static_s = static_s;
  sim.transition_s = 2;
  sim.sigma_raw_per_sample = Vec3::Constant(2e-3);
  const SimulatedLog simulated = SimulateRawLog(truth, 1.0, directions, sim);
  Recording r;
  r.log.source = "simulated.csv";
  r.log.time_s = simulated.time_s;
  r.log.samples = simulated.samples;
  r.log.line.resize(r.log.samples.size(), 1);
  r.log.rate_hz = sim.rate_hz;
  r.detection = DetectStaticIntervals(r.log, StaticDetectionOptions());
  std::vector<Position> positions = PositionsFromIntervals(r.detection.intervals);
  if (moved >= 0) positions[static_cast<std::size_t>(moved)].mean += Vec3(0.02, -0.02, 0.02);
  CalibrationOptions options;
  options.model = model;
  options.gravity = 1.0;
  options.reading_sigmas = SigmasOfMeans(positions);
  options.outliers.policy = outliers;
  CalibrationResult result = Calibrate(Means(positions), options);
  CrossValidate(Means(positions), options, &result);
  CalibrationFileInfo info;
  info.unit = ForceUnit::kStandardGravity;
  info.raw_unit = "g";
  info.source = "simulated.csv";
  info.positions = positions;
  r.json = CalibrationToJson(result, info);
  r.cal = ParseCalibrationJson(r.json, "cal.json");
  return r;
}

TEST(Report, SelfContainedPageWithEveryPlotAndTheParameterTable) {
  const Recording r = Record(Yang18Directions(), ModelKind::kQuadratic);
  ASSERT_EQ(r.detection.intervals.size(), 18u);
  ReportInput input{r.cal, "cal.json", &r.log, r.detection.rejected};
  const std::string html = RenderReport(input);
  for (const char* id : {"raw-signal", "norm-error", "sphere", "residuals"}) {
    EXPECT_EQ(Count(html, std::string("<svg id=\"") + id + "\""), 1u) << id;
  }
  EXPECT_EQ(Count(html, "<svg "), Count(html, "</svg>"));
  // One shaded interval and one number per position, one dot per direction, one held-out circle.
  EXPECT_EQ(Count(html, "<rect class=\"interval\""), 18u);
  EXPECT_EQ(Count(html, "<circle class=\"direction\""), 18u);
  EXPECT_EQ(Count(html, "<circle class=\"held-out\""), 18u);
  EXPECT_EQ(Count(html, "<circle class=\"after\""), 18u);
  EXPECT_EQ(Count(html, "<rect class=\"before\""), 18u);  // readings in g: |p| − g means something
  // Scale factors, three misalignments, biases, squared coefficients, each with its 1σ.
  EXPECT_EQ(Count(html, "<tr><td>"), 12u);
  EXPECT_EQ(Count(html, "&plusmn; "), 12u);
  // Nothing is fetched: no scripts, links, images or external styles (the SVG namespace is a name,
  // not a request).
  for (const char* external : {"<script", "src=", "href=", "url(", "<link", "@import"}) {
    EXPECT_EQ(Count(html, external), 0u) << external;
  }
  EXPECT_EQ(Count(html, "http"), Count(html, "xmlns=\"http://www.w3.org/2000/svg\""));
  EXPECT_EQ(RenderReport(input), html);                     // deterministic
  EXPECT_NE(html.find("<p>None.</p>"), std::string::npos);  // a clean recording: no warnings
}

TEST(Report, ShowsTheGyroscopeItsTurnsAndItsStillRates) {
  // A gyroscope section added to the file (as calibrate --gyro writes it: the keys the report
  // reads): its parameters ±1σ, a fitted and a held-out error per turn, and per position the
  // still rate less the bias beside G f on each axis.
  const Recording r = Record(Yang18Directions(), ModelKind::kLinear);
  nlohmann::json doc = nlohmann::json::parse(r.json);
  nlohmann::json g;
  g["model"] = "g-sensitive";
  g["estimator"] = "joint";
  g["units"] = {{"raw", "counts"}};
  g["K"] = {{4778, 12, -8}, {-15, 4758, 20}, {9, -11, 4766}};
  g["bias"] = {32740, 32810, 32650};
  g["g_sensitivity"] = {{1.5, -0.4, 0.2}, {0.3, -1.1, 0.6}, {-0.2, 0.5, 0.9}};
  nlohmann::json covariance = nlohmann::json::array();
  for (int i = 0; i < 21; ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (int j = 0; j < 21; ++j) row.push_back(i == j ? 0.25 : 0.0);
    covariance.push_back(row);
  }
  g["covariance"] = covariance;
  g["rotations"] = nlohmann::json::array();
  for (int k = 1; k < 18; ++k) {
    g["rotations"].push_back({{"from", k},
                              {"to", k + 1},
                              {"residual_deg", 0.01 * k},
                              {"heldout_deg", 0.012 * k},
                              {"turned_deg", 90.0}});
  }
  g["stills"] = nlohmann::json::array();
  for (int k = 1; k <= 18; ++k) {
    g["stills"].push_back({{"position", k}, {"mean_raw", {32740 + k, 32810 - k, 32650}}});
  }
  g["validation"] = {{"rms_deg", 0.1}, {"heldout_rms_deg", 0.12}};
  doc["sensors"]["gyroscope"] = g;
  const LoadedCalibration cal = ParseCalibrationJson(doc.dump(), "imu.json");
  ASSERT_TRUE(cal.has_gyroscope());
  ASSERT_EQ(cal.gyroscope->rotations.size(), 17u);
  ASSERT_EQ(cal.gyroscope->still_spans.size(), 18u);
  ReportInput input{cal, "imu.json", &r.log, r.detection.rejected};
  const std::string html = RenderReport(input);
  for (const char* id : {"gyro-rotations", "gyro-stills"}) {
    EXPECT_EQ(Count(html, std::string("<svg id=\"") + id + "\""), 1u) << id;
  }
  EXPECT_EQ(Count(html, "<svg "), Count(html, "</svg>"));
  // The linear accelerometer's 9 rows and the gyro's 21 (K, b, G per axis), each with its 1σ.
  EXPECT_EQ(Count(html, "<tr><td>"), 9u + 21u);
  EXPECT_EQ(Count(html, "&plusmn; 0.5<"), 21u);
  // Per turn a fitted and a held-out circle beside the accelerometer's 18 of each; per position
  // and axis a measured dot and a modelled ring.
  EXPECT_EQ(Count(html, "<circle class=\"after\""), 18u + 17u);
  EXPECT_EQ(Count(html, "<circle class=\"held-out\""), 18u + 17u);
  EXPECT_EQ(Count(html, " G f: "), 54u);
  EXPECT_EQ(Count(html, " measured: "), 54u);
  EXPECT_NE(html.find("held out 0.12 deg"), std::string::npos);
  // A rotation record without its residual is refused by name.
  doc["sensors"]["gyroscope"]["rotations"][3].erase("residual_deg");
  try {
    ParseCalibrationJson(doc.dump(), "imu.json");
    ADD_FAILURE() << "a rotation without its residual was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rotations[].residual_deg"), std::string::npos)
        << e.what();
  }
  // A position that is not a count from 1, a negative angle: refused by name.
  doc["sensors"]["gyroscope"]["rotations"][3]["residual_deg"] = 0.03;
  for (const auto& [key, value] :
       {std::pair("from", 0.0), std::pair("to", 2.5), std::pair("residual_deg", -0.1),
        std::pair("heldout_deg", -1.0), std::pair("turned_deg", -90.0)}) {
    nlohmann::json bad = doc;
    bad["sensors"]["gyroscope"]["rotations"][3][key] = value;
    try {
      ParseCalibrationJson(bad.dump(), "imu.json");
      ADD_FAILURE() << key << " " << value << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("rotations[].") + key), std::string::npos)
          << e.what();
    }
  }
  EXPECT_NO_THROW(ParseCalibrationJson(doc.dump(), "imu.json"));
}

TEST(Report, WarnsAboutAMovedPositionAGapInCoverageAndUnusedStillPeriods) {
  // Position 5's mean pushed by 0.035 g: far beyond the held-out error of the others. The
  // calibration's screening leaves it out, and the report says so (and nothing else).
  const Recording moved = Record(Yang18Directions(), ModelKind::kLinear, 4.0, 4);
  std::vector<std::string> w = ReportWarnings({moved.cal, "cal.json", nullptr, {}});
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("position 5 disagrees with the others (t = -", 0), 0u) << w[0];
  EXPECT_NE(w[0].find("): left out of the fit;"), std::string::npos) << w[0];
  // A file calibrated with the screening off: two warnings, the scatter the position causes,
  // beyond the interval noise, and the position itself by its held-out error (and no other).
  const Recording kept =
      Record(Yang18Directions(), ModelKind::kLinear, 4.0, 4, OutlierPolicy::kOff);
  w = ReportWarnings({kept.cal, "cal.json", nullptr, {}});
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].rfind("the positions scatter ", 0), 0u) << w[0];
  EXPECT_EQ(w[1].rfind("position 5: held-out |f| - g = ", 0), 0u) << w[1];
  // All positions within 60° of +z: nothing near -z.
  const Recording cap = Record(RandomDirectionsInCap(14, kPi / 3, 9), ModelKind::kLinear);
  bool gap = false;
  for (const std::string& s : ReportWarnings({cap.cal, "cal.json", nullptr, {}})) {
    gap = gap || s.rfind("no position within ", 0) == 0;
  }
  EXPECT_TRUE(gap);
  // Tilted at most 30°: the scale factors and biases are barely determined, and said to be.
  const Recording narrow = Record(RandomDirectionsInCap(14, kPi / 6, 9), ModelKind::kLinear);
  int poorly = 0;
  for (const std::string& s : ReportWarnings({narrow.cal, "cal.json", nullptr, {}})) {
    if (s.rfind("poorly determined: ", 0) != 0) continue;
    for (std::size_t at = 0; (at = s.find(" (1 sigma ", at)) != std::string::npos; ++at) ++poorly;
  }
  EXPECT_GE(poorly, 4);
  // A rejected still period is listed with its reason: a clipped one as a warning (a position
  // the user meant to record is lost), a short one as a note.
  RejectedInterval clipped;
  clipped.t_begin_s = 3.5;
  clipped.t_end_s = 4.1;
  clipped.cause = RejectedInterval::Cause::kClipped;
  clipped.reason = "axis y reads 40000, the largest value in the log, in 100% of its samples";
  const std::vector<std::string> with_rejected =
      ReportWarnings({moved.cal, "cal.json", nullptr, {clipped}});
  EXPECT_EQ(with_rejected.back(),
            "the still period 3.500-4.100 s is not used: axis y reads 40000, the largest value in "
            "the log, in 100% of its samples");
}

TEST(StaticDetection, StillRunsTooShortAreReportedAsRejected) {
  // Still 0.7 s between turns: detected as still but shorter than the 1 s minimum.
  const Recording r = Record(Yang18Directions(), ModelKind::kLinear, 1.2);
  ASSERT_FALSE(r.detection.rejected.empty());
  for (const RejectedInterval& rej : r.detection.rejected) {
    EXPECT_LT(rej.t_end_s - rej.t_begin_s, 1.0);
    EXPECT_NE(rej.reason.find("shorter than the minimum 1.00 s"), std::string::npos);
  }
}

TEST(Report, IsMadeOnlyFromAFileThatReadsAsACalibration) {
  // The report takes the file as read: what is no calibration is refused by the reader, with the
  // key's place in the file.
  EXPECT_THROW(ParseCalibrationJson("{\"format\": \"other\"}", "x.json"), InputError);
  // Found by fuzz_calibration_file: a covariance of the wrong size was read past its end, and a
  // field of the wrong type escaped as a JSON exception. Both are now the file's error.
  const Recording r = Record(Yang18Directions(), ModelKind::kLinear);
  nlohmann::ordered_json doc = nlohmann::ordered_json::parse(r.json);
  doc["sensors"]["accelerometer"]["covariance"] = {{1.0, 0.0}, {0.0, 1.0}};
  try {
    ParseCalibrationJson(doc.dump(), "x.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "x.json: 'sensors.accelerometer.covariance' must be null or a 9x9 array (the linear "
              "model in frame x-first)");
  }
  // Found by fuzz_calibration_file: a number beyond double's range escaped as a JSON exception.
  try {
    ParseCalibrationJson("{\"format\": \"accelcal-calibration\", \"gravity\": 1e708}", "x.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x.json: not valid JSON: "), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("number overflow"), std::string::npos) << e.what();
  }
  doc = nlohmann::ordered_json::parse(r.json);
  doc["sensors"]["accelerometer"]["solver"] = {{"method", 5}};
  try {
    ParseCalibrationJson(doc.dump(), "x.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "x.json: 'sensors.accelerometer.solver.method' must be text");
  }
}

}  // namespace
}  // namespace accelcal
