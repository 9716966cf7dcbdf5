// Paper 003 §5, system-level calibration (system_level.hpp): the printed equations as known
// answers, Table 4 against them (docs/errata.md#003-table4), and the estimator on a simulated day.
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/series_file.hpp"
#include "accelcal/system_level.hpp"

namespace accelcal {
namespace {

constexpr double kLatitude = 40.0 * 3.14159265358979323846 / 180.0;

// Eq. (21)-(25), (29)-(38) with Tables 2-3, L = 40°, g = 9.801696862780418 m/s² (WGS-84 normal
// gravity at 40° to 1e-11), evaluated independently (Python, double precision).
constexpr double kG = 9.801696862780418;
const std::map<std::string, double> kPrinted = {
    {"x1", -1.8873195215442275e-05},      {"x2", -8.6441539731891973e-05},
    {"x3", 8.2174798268912306e-05},       {"x4", -5.0000000000000002e-05},
    {"x5", 1.2120342027738399e-05},       {"pitch_mean", 0.00020125523709086667},
    {"pitch_c1", 3.1322866646410054e-05}, {"pitch_s1", -2.858025810027092e-05},
    {"pitch_c2", -2.46201938253052e-05},  {"pitch_s2", 5.96810339903824e-06},
    {"roll_mean", 2.785416197715122e-05}, {"roll_s1", -7.0859928370705432e-05},
    {"roll_c1", -6.6593186907725778e-05}, {"roll_s2", 3.8302222155948904e-05},
    {"roll_c2", 9.284720659050406e-06}};

std::map<std::string, double> Flatten(const CombinedCoefficients& c) {
  return {{"x1", c.x(0)},
          {"x2", c.x(1)},
          {"x3", c.x(2)},
          {"x4", c.x(3)},
          {"x5", c.x(4)},
          {"pitch_mean", c.pitch.mean},
          {"pitch_c1", c.pitch.c1},
          {"pitch_s1", c.pitch.s1},
          {"pitch_c2", c.pitch.c2},
          {"pitch_s2", c.pitch.s2},
          {"roll_mean", c.roll.mean},
          {"roll_s1", c.roll.s1},
          {"roll_c1", c.roll.c1},
          {"roll_s2", c.roll.s2},
          {"roll_c2", c.roll.c2}};
}

TEST(SystemLevel, CombinedCoefficientsFollowThePrintedEquations) {
  const std::map<std::string, double> c =
      Flatten(CombinedFromResiduals(Wu2018Residuals(), kLatitude, kG));
  for (const auto& [name, value] : kPrinted) {
    // 1e-12 absolute (rad), as the issue asks; measured 3e-16 (the last bits of sin and cos).
    EXPECT_NEAR(c.at(name), value, 1e-12) << name;
    EXPECT_NEAR(c.at(name), value, 1e-10 * std::abs(value)) << name;
  }
}

TEST(SystemLevel, Table4ReferenceValuesThatDoNotFollowFromThePrintedEquations) {
  // docs/errata.md#003-table4: Table 4's "reference values" (4 significant digits) agree with the
  // printed equations for x2..x5, δφ2s, δθ2c, and not for the rest, which need sign flips of bias
  // or Δβ terms.
  const std::map<std::string, double> table4 = {
      {"x1", 1.1228e-4},       {"x2", -8.645e-5},       {"x3", 8.217e-5},
      {"x4", -5.000e-5},       {"x5", 1.212e-5},        {"roll_s1", -1.3319e-4},
      {"roll_c1", -3.542e-5},  {"roll_s2", 3.830e-5},   {"roll_c2", -9.28e-6},
      {"pitch_s1", -5.521e-5}, {"pitch_c1", 1.3629e-4}, {"pitch_s2", -5.97e-6},
      {"pitch_c2", -2.462e-5}};
  const std::map<std::string, bool> agrees = {
      {"x1", false},      {"x2", true},        {"x3", true},        {"x4", true},
      {"x5", true},       {"roll_s1", false},  {"roll_c1", false},  {"roll_s2", true},
      {"roll_c2", false}, {"pitch_s1", false}, {"pitch_c1", false}, {"pitch_s2", false},
      {"pitch_c2", true}};
  for (const auto& [name, reference] : table4) {
    // Agreement: within 0.1 % (the table's 4 digits and its g, docs/errata.md#003-table4 best
    // fit g ≈ 9.802, leave 1e-4 relative: x2 is printed −8.6442e-5 against −8.645e-5); the others
    // are off by sign flips or other terms, tens of percent and more.
    EXPECT_EQ(std::abs(kPrinted.at(name) - reference) <= 1e-3 * std::abs(reference),
              agrees.at(name))
        << name << ": printed " << kPrinted.at(name) << ", Table 4 " << reference;
  }
}

TEST(SystemLevel, RecoversTheCoefficientsOfASimulatedDayWithinTheirUncertainty) {
  // Paper 003 §6.1: Tables 2-3, L = 40°, 5e-3 m/s² per axis, 100 Hz, 24 h (8.64 million samples).
  SystemSimulationOptions o;
  const double g = NormalGravityWgs84_ms2(o.latitude_deg);
  SystemLevelOptions options;
  options.latitude_rad = kLatitude;
  options.gravity_ms2 = g;
  SystemLevelEstimator estimator(options);
  SimulateSystemLevel(o, [&](const SystemSample& s) { estimator.Add(s); });
  const SystemLevelResult r = estimator.Finish();
  EXPECT_EQ(r.samples, 8640000);
  EXPECT_EQ(r.summary.termination, TerminationType::kClosedForm);
  EXPECT_TRUE(r.summary.converged());
  EXPECT_EQ(r.summary.iterations, 0);
  EXPECT_NE(r.summary.termination_message.find("rank 4 of 6"), std::string::npos)
      << r.summary.termination_message;
  const CombinedCoefficients truth = CombinedFromResiduals(o.errors, kLatitude, g);
  for (int i = 0; i < 5; ++i) {
    // The bounds: within 4σ, σ between 1e-7 and 5e-7 (the paper's errors 1.1-4.3e-7).
    EXPECT_NEAR(r.x(i), truth.x(i), 4 * r.x_std(i)) << "x" << i + 1;
    EXPECT_GT(r.x_std(i), 1e-7) << "x" << i + 1;
    EXPECT_LT(r.x_std(i), 5e-7) << "x" << i + 1;
  }
  // docs/errata.md#003-eq20: without the correction x1 would sit E|n|²/(2g²) = 3.9e-7 high, 2σ.
  EXPECT_NEAR(r.x1_noise_correction, 3 * 25e-6 / (2 * g * g), 1e-9);
  EXPECT_NEAR(r.noise_ms2(0), 5e-3, 5e-3 * 0.01);
  const auto check = [](const FourierCoefficients& e, const FourierCoefficients& sd,
                        const FourierCoefficients& t, const char* which) {
    EXPECT_NEAR(e.mean, t.mean, 4 * sd.mean) << which;
    EXPECT_NEAR(e.c1, t.c1, 4 * sd.c1) << which;
    EXPECT_NEAR(e.s1, t.s1, 4 * sd.s1) << which;
    EXPECT_NEAR(e.c2, t.c2, 4 * sd.c2) << which;
    EXPECT_NEAR(e.s2, t.s2, 4 * sd.s2) << which;
  };
  check(r.pitch, r.pitch_std, truth.pitch, "pitch");
  check(r.roll, r.roll_std, truth.roll, "roll");

  // Separation: rank 4; Δβzy and Δβzx determined, ∇x/g, ∇y/g, Δβyx, Δβxy only in combination.
  EXPECT_EQ(r.rank, 4);
  const std::vector<std::string> expected_undetermined = {"nabla_x/g", "nabla_y/g", "dbeta_yx",
                                                          "dbeta_xy"};
  EXPECT_EQ(r.undetermined, expected_undetermined);
  const ResidualErrors& e = o.errors;
  const double sL = std::sin(kLatitude);
  const std::map<std::string, double> separated_truth = {
      {"dSFx/(2SFx) - dSFy/(2SFy)", e.scale(0) / 2 - e.scale(1) / 2},
      {"(dbeta_yz - dbeta_xz)/2", (e.beta_yz - e.beta_xz) / 2},
      {"dbeta_zx", e.beta_zx},
      {"dbeta_zy", e.beta_zy},
      {"nabla_x/g - 0.642788*dbeta_xy", e.bias_ms2(0) / g - sL * e.beta_xy},
      {"nabla_y/g + 0.642788*dbeta_yx", e.bias_ms2(1) / g + sL * e.beta_yx}};
  ASSERT_EQ(r.determined.size(), separated_truth.size());
  for (const Estimate& d : r.determined) {
    ASSERT_TRUE(separated_truth.count(d.name)) << d.name;
    EXPECT_NEAR(d.value, separated_truth.at(d.name), 4 * d.std) << d.name;
    EXPECT_GT(d.std, 0.0) << d.name;
  }
}

TEST(SystemLevel, SeriesFilesRoundTripInBothLayouts) {
  SystemSimulationOptions o;
  o.duration_s = 10;
  std::vector<SystemSample> samples;
  SimulateSystemLevel(o, [&](const SystemSample& s) { samples.push_back(s); });
  ASSERT_EQ(samples.size(), 1000u);
  std::string binary;
  AppendSeriesHeader(&binary);
  std::string text = "t,fx,fy,fz,roll,pitch\n";
  for (const SystemSample& s : samples) {
    AppendSeriesSample(s, &binary);
    char row[256];
    std::snprintf(row, sizeof row, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", s.t, s.f(0), s.f(1),
                  s.f(2), s.roll, s.pitch);
    text += row;
  }
  EXPECT_EQ(binary.size(), kSeriesMagic.size() + 48 * 1000);
  for (const std::string* content : {&binary, &text}) {
    std::size_t k = 0;
    ParseSeries(*content, "s", [&](const SystemSample& s) {
      ASSERT_LT(k, samples.size());
      EXPECT_EQ(s.t, samples[k].t);
      EXPECT_EQ(s.f, samples[k].f);
      EXPECT_EQ(s.roll, samples[k].roll);
      EXPECT_EQ(s.pitch, samples[k].pitch);
      ++k;
    });
    EXPECT_EQ(k, samples.size());
  }
  // Progress for a bar: every 65536 samples, bytes done increasing, of one total.
  std::string long_binary;
  AppendSeriesHeader(&long_binary);
  for (int r = 0; r < 200; ++r) long_binary.append(binary, kSeriesMagic.size(), std::string::npos);
  std::vector<std::pair<std::size_t, std::size_t>> reports;
  ParseSeries(
      long_binary, "s", [](const SystemSample&) {},
      [&](std::size_t done, std::size_t total) { reports.emplace_back(done, total); });
  ASSERT_EQ(reports.size(), 4u);  // samples 0, 65536, 131072, 196608 of 200000
  for (std::size_t r = 0; r < reports.size(); ++r) {
    EXPECT_EQ(reports[r].first, r * 65536 * 48);
    EXPECT_EQ(reports[r].second, 200000u * 48);
  }
  const auto error = [](const std::string& content) {
    try {
      ParseSeries(content, "s.bin", [](const SystemSample&) {});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error(binary.substr(0, binary.size() - 5)),
            "s.bin: truncated binary series: 47995 bytes after the header is not a whole number "
            "of 48-byte samples");
  EXPECT_EQ(error("t,fx,fy,fz,roll,pitch\n1,2,3,4,5,6\n1,2,3\n"),
            "s.bin:3: expected 6 numbers (t,fx,fy,fz,roll,pitch)");
  EXPECT_EQ(error("1,2,3,4,5,nan\n"), "s.bin:1: a value is not finite");
  EXPECT_EQ(error("# nothing\n"), "s.bin: no samples in the series");
  EXPECT_EQ(error("accelcal-series 2 whatever\n").rfind("s.bin:1: unsupported binary series", 0),
            0u);
}

TEST(SystemLevel, RefusesTooShortASeries) {
  SystemLevelOptions options;
  options.latitude_rad = kLatitude;
  options.gravity_ms2 = 9.8;
  SystemLevelEstimator estimator(options);
  SystemSimulationOptions o;
  o.duration_s = 3600;  // 0.26 rad of platform angle
  SimulateSystemLevel(o, [&](const SystemSample& s) { estimator.Add(s); });
  EXPECT_THROW(estimator.Finish(), DataError);
  // The requirement is an option: a quarter radian suffices when asked for.
  options.min_platform_angle_rad = 0.25;
  SystemLevelEstimator lenient(options);
  SimulateSystemLevel(o, [&](const SystemSample& s) { lenient.Add(s); });
  EXPECT_EQ(lenient.Finish().summary.termination, TerminationType::kClosedForm);
}

TEST(SystemLevel, OptionsAreValidatedWithoutNamingFlags) {
  SystemLevelOptions options;  // no latitude
  ASSERT_TRUE(options.Validate().has_value());
  EXPECT_THROW(SystemLevelEstimator{options}, std::invalid_argument);
  options.latitude_rad = 0.5 * 3.14159265358979323846 / 180;  // within 1° of the equator
  ASSERT_TRUE(options.Validate().has_value());
  EXPECT_NE(options.Validate()->find("equator"), std::string::npos);
  options.latitude_rad = kLatitude;
  EXPECT_FALSE(options.Validate().has_value());
  options.gravity_ms2 = -1;
  ASSERT_TRUE(options.Validate().has_value());
  EXPECT_EQ(options.Validate()->find("--"), std::string::npos);
  options.gravity_ms2 = 0;  // WGS-84 normal gravity at the latitude
  EXPECT_EQ(SystemLevelEstimator(options).gravity_ms2(), NormalGravityWgs84_ms2(40.0));
  options.rank_tolerance = 0;
  EXPECT_TRUE(options.Validate().has_value());
}

}  // namespace
}  // namespace accelcal
