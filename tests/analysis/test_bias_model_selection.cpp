// --bias-model auto: the bias model the data support (model_selection.hpp SelectBiasModel), on
// the bundled recordings and on simulated devices with and without a drift.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/log_reader.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/static_detection.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

const std::string kData = ACCELCAL_DATA_DIR;

bool StartsWith(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

// The positions of a raw log and their middle times.
struct TimedPositions {
  std::vector<Vec3> means;
  std::vector<double> times;
};
TimedPositions FromLog(const std::string& path) {
  const InputData d = ReadInput(path, {});
  TimedPositions out;
  for (const Position& p : PositionsFromIntervals(DetectStaticIntervals(d.raw, {}).intervals)) {
    out.means.push_back(p.mean);
    out.times.push_back(0.5 * (p.interval->t_begin_s + p.interval->t_end_s));
  }
  return out;
}
// A positions file taken in its rows' order, one row a second (the sets without times).
TimedPositions FromRows(const std::string& path) {
  const InputData d = ReadInput(path, {});
  TimedPositions out;
  for (const Position& p : d.positions) {
    out.means.push_back(p.mean);
    out.times.push_back(static_cast<double>(out.times.size()));
  }
  return out;
}

CalibrationOptions Options(double gravity, const std::vector<double>& times) {
  CalibrationOptions o;
  o.gravity = gravity;
  o.cross_validate = true;
  o.position_times_s = times;
  return o;
}

// The T265 session drifts (x by about −0.66 mg a minute over its 6 minutes): the linear bias is
// chosen and predicts held-out positions at 0.35 mg, where the constant bias gives 0.64 mg (issue
// 21 asks for 0.40 mg or better).
TEST(BiasModelSelection, T265DriftsAndALinearBiasHalvesTheHeldOutError) {
  const double g = 9.80665;
  const TimedPositions t265 = FromLog(kData + "/imutk-t265/t265_acc.mat");
  ASSERT_EQ(t265.means.size(), 44u);
  const BiasModelSelection s = SelectBiasModel(t265.means, Options(g, t265.times));
  EXPECT_EQ(ToString(s.chosen), "linear") << s.reason;
  ASSERT_TRUE(s.result.crossval_rms);
  const double held_out_mg = *s.result.crossval_rms / g * 1e3;
  EXPECT_LE(held_out_mg, 0.40);
  EXPECT_NEAR(held_out_mg, 0.346, 0.002);  // measured; the prototype of the issue had 0.335
  ASSERT_FALSE(s.steps.empty());
  const BiasModelStep& first = s.steps.front();
  EXPECT_TRUE(first.accepted);
  EXPECT_NEAR(first.simpler_rms / g * 1e3, 0.638, 0.002);  // the constant bias
  EXPECT_GT(first.wald, 4 * first.wald_threshold);
  // x drifts by −0.665 mg a minute (σ 0.057): the rest's own slope is the same sign.
  ASSERT_TRUE(s.result.drift);
  const double x_mg_per_min = s.result.drift->D(0, 0) / g * 1e3;
  EXPECT_NEAR(x_mg_per_min, -0.665, 0.01);
}

// The Xsens session warms up: its first rest drifts by 24 mg in 52 s and levels off. No straight
// line follows that (the linear bias predicts held-out positions worse, 0.149 against 0.143 mg),
// a spline over 3 knots does: 0.102 mg.
TEST(BiasModelSelection, XsensWarmUpIsFollowedByASplineNotALine) {
  const double g = 9.81744;
  const TimedPositions xsens = FromLog(kData + "/imutk-xsens-mti/xsens_acc.mat");
  const BiasModelSelection s = SelectBiasModel(xsens.means, Options(g, xsens.times));
  EXPECT_EQ(ToString(s.chosen), "spline:3") << s.reason;
  ASSERT_GE(s.steps.size(), 2u);
  EXPECT_FALSE(s.steps[0].accepted);  // linear
  EXPECT_GT(s.steps[0].simpler_rms, 0.99 * s.steps[0].richer_rms * 0.96);
  EXPECT_TRUE(s.steps[1].accepted);  // spline:3 against the constant bias
  EXPECT_NEAR(s.steps[1].simpler_rms / g * 1e3, 0.143, 0.001);
  EXPECT_NEAR(*s.result.crossval_rms / g * 1e3, 0.102, 0.001);
  for (std::size_t i = 2; i < s.steps.size(); ++i) EXPECT_FALSE(s.steps[i].accepted) << i;
}

// Recordings without a drift the data can show keep the constant bias, their held-out error
// unchanged: the CTU sets and the CK blocks (rows in recorded order, a second apart).
TEST(BiasModelSelection, RecordingsWithoutADriftKeepTheConstantBias) {
  struct Set {
    TimedPositions positions;
    double gravity;
  };
  std::vector<Set> sets;
  for (const char* file : {"measured_accelerations_24pos.csv", "measured_accelerations_49pos.csv",
                           "hassan_subset_31pos.csv"}) {
    sets.push_back({FromRows(kData + "/ctu-innalabs-ahrs-m3/" + file), 1.0});
  }
  sets.push_back(
      {FromRows(kData + "/ckexplorer-160blocks/derived_block_means_rows10to89.csv"), 1.0});
  for (const Set& set : sets) {
    const CalibrationOptions o = Options(set.gravity, set.positions.times);
    const BiasModelSelection s = SelectBiasModel(set.positions.means, o);
    EXPECT_TRUE(s.chosen.constant()) << set.positions.means.size() << ": " << s.reason;
    EXPECT_FALSE(s.result.drift);
    ASSERT_FALSE(s.steps.empty());
    EXPECT_FALSE(s.steps.front().accepted);
    EXPECT_TRUE(StartsWith(s.reason,
                           "no bias model that follows time passes the evidence rule: "
                           "linear does not"))
        << s.reason;
    CalibrationOptions constant = o;
    constant.position_times_s.clear();
    const CalibrationResult c = Calibrate(set.positions.means, constant);
    ASSERT_TRUE(s.result.crossval_rms && c.crossval_rms);
    EXPECT_EQ(*s.result.crossval_rms, *c.crossval_rms);  // never worse: the same fit
  }
}

// Without times there is nothing to choose from; with one time for all positions neither.
TEST(BiasModelSelection, PositionsWithoutTimesKeepTheConstantBias) {
  const std::vector<Vec3> readings =
      SimulatePositions(Yang2012Truth(), kYang2012Gravity_ms2, RandomDirections(24, 3),
                        Yang2012SigmaRaw(Yang2012Truth()), 3);
  CalibrationOptions o = Options(kYang2012Gravity_ms2, {});
  o.model = ModelKind::kQuadratic;
  const BiasModelSelection s = SelectBiasModel(readings, o);
  EXPECT_TRUE(s.chosen.constant());
  EXPECT_EQ(s.reason, "the positions have no times");
  EXPECT_TRUE(s.steps.empty());
}

// Simulated: a device whose bias drifts by 20 σ over the session gets the linear bias in every
// run; a device without a drift keeps the constant bias in most (the rule passes a drift that is
// not there only when both its tests do, each at 5 %).
TEST(BiasModelSelection, SimulatedDriftIsFoundAndNoDriftIsNotInvented) {
  const int m = 30, runs = 40;
  ModelParameters device = Yang2012Truth();
  device.k2.setZero();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  std::vector<double> times;
  for (int k = 0; k < m; ++k) times.push_back(5.0 + 20.0 * k);
  int drift_found = 0, drift_invented = 0;
  for (int run = 1; run <= runs; ++run) {
    const auto seed = static_cast<std::uint64_t>(run);
    const std::vector<Vec3> dirs = RandomDirections(m, 300 + seed);
    std::vector<Vec3> readings = SimulatePositions(device, kYang2012Gravity_ms2, dirs, sigma, seed);
    const BiasModelSelection quiet =
        SelectBiasModel(readings, Options(kYang2012Gravity_ms2, times));
    drift_invented += quiet.chosen.constant() ? 0 : 1;
    for (int k = 0; k < m; ++k) {
      readings[std::size_t(k)] += 20.0 * sigma * (times[std::size_t(k)] - 295.0) / 580.0;
    }
    const BiasModelSelection drifting =
        SelectBiasModel(readings, Options(kYang2012Gravity_ms2, times));
    drift_found += drifting.chosen.kind == BiasModelKind::kLinear ? 1 : 0;
  }
  EXPECT_EQ(drift_found, runs);
  // Measured: 0 of 40. Binomial at 5 %: 6 or more in 40 has probability 0.05.
  EXPECT_LE(drift_invented, 5);
}

}  // namespace
}  // namespace accelcal
