// The gyroscope's findings (GyroFindings, diagnosis.hpp): its fit, its turns and still positions,
// its unit and its lag behind the accelerometer.
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "accelcal/diagnosis.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "analysis/findings.hpp"
#include "core/text_format.hpp"

namespace accelcal {

using internal::AddFinding;
using internal::Format;

namespace {

// How well the rotations fit, their scatter, what the turns barely determine, mirrored axes, and
// turns that disagree with the others.
void GyroFitFindings(const GyroCalibration& g, std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  const double ratio = g.rotation_scatter_ratio;
  if (g.rms_deg > kGyroMisfitFailure_deg && !(ratio <= kScatterWarning)) {
    AddFinding(
        &out, "gyro_misfit", Severity::kFailure,
        Format("the gyroscope's rotations miss the gravity directions by %.3g deg RMS, %.3g times "
               "what its rate noise explains, beyond %.0f deg: its calibration does not fit (its "
               "axes mapped otherwise than the accelerometer's, a rate axis saturated, or a model "
               "without a term this gyro has%s)",
               g.rms_deg, ratio, kGyroMisfitFailure_deg,
               g.estimator != GyroEstimator::kJoint
                   ? "; the accelerometer's calibration was held, and the rotations may contradict "
                     "it: the joint estimator fits both"
                   : ""),
        {{"rms_deg", g.rms_deg}, {"scatter_ratio", ratio}, {"limit_deg", kGyroMisfitFailure_deg}});
  }
  const struct {
    const char* what;
    double ratio;
  } groups[] = {{"still rates", g.still_scatter_ratio}, {"rotations", g.rotation_scatter_ratio}};
  for (const auto& group : groups) {
    if (!(group.ratio > kScatterNote)) continue;
    const bool warn = group.ratio > kScatterWarning;
    AddFinding(
        &out, "gyro_scatter_ratio", warn ? Severity::kWarning : Severity::kNote,
        Format("the gyroscope's %s scatter %.3g times more than its rate noise explains%s; its "
               "uncertainties are inflated by that factor",
               group.what, group.ratio,
               warn ? ": something other than noise dominates (a bias drifting, turns not "
                      "integrated faithfully, a model that does not fit this gyro)"
                    : ""),
        {{"scatter_ratio", group.ratio}});
  }
  // The accelerometer's rule for a calibration worth applying: a scale factor to 1 %, a
  // misalignment to 0.5° (K_g's off-diagonal terms over their row's scale, in radians).
  if (g.covariance.size() > 0) {
    const auto& slots = GyroParameterSlots(g.model);
    std::string names;
    double worst = 0;
    for (std::size_t p = 0; p < slots.size(); ++p) {
      const GyroParameterSlot& s = slots[p];
      if (s.group != GyroParameterGroup::kK) continue;
      const auto i = static_cast<Eigen::Index>(p);
      // Relative to its row's length (a gyro mounted turned has a diagonal near 0): its scale
      // the row's largest entry (the diagonal when aligned), its misalignments the others.
      const double scale = g.params.K.row(s.row).norm();
      Eigen::Index largest = 0;
      g.params.K.row(s.row).cwiseAbs().maxCoeff(&largest);
      const double sigma = std::sqrt(g.covariance(i, i)) / scale;  // relative, or radians
      const double limit = s.col == largest ? kGyroScaleSigmaLimit : kGyroMisalignmentSigmaLimit;
      if (!(sigma <= limit)) {
        names += (names.empty() ? "" : ", ") + std::string(s.name);
        worst = std::max(worst, sigma / limit);
      }
    }
    if (!names.empty()) {
      // Ten times beyond (10 % of a scale, 5° of a misalignment): not a calibration at all.
      AddFinding(
          &out, "gyro_poorly_determined", worst > 10 ? Severity::kFailure : Severity::kWarning,
          Format("the turns barely determine the gyroscope's %s (up to %.3g times the 1 %% of a "
                 "scale or 0.5 deg of a misalignment a calibration worth applying has): turn "
                 "about every axis, several times",
                 names.c_str(), worst),
          {{"worst_ratio", worst}});
    }
  }
  if (g.params.K.determinant() < 0) {
    AddFinding(
        &out, "gyro_mirrored", Severity::kWarning,
        "the gyroscope's axes are mirrored against the accelerometer's (det K_g < 0: one axis "
        "reads inverted, or two are swapped): the calibration maps the rates as they are, but a "
        "driver's or log's axis setting is likely wrong; check the gyro's axis signs and order",
        {{"det_K", g.params.K.determinant()}});
  }
  for (const GyroRotation& r : g.rotations) {
    if (!r.flagged) continue;
    AddFinding(
        &out, "gyro_turn_outlier", Severity::kWarning,
        Format("the turn from position %zu to %zu (samples %zu-%zu, %.3g s) disagrees with the "
               "others: its held-out chi^2 %.3g is beyond %.3g (1 %% over all turns); a bump "
               "during it? It was kept in the fit",
               r.from + 1, r.to + 1, r.first_sample + 1, r.last_sample + 1, r.duration_s,
               r.statistic, r.threshold),
        {{"from", static_cast<double>(r.from + 1)},
         {"to", static_cast<double>(r.to + 1)},
         {"statistic", r.statistic},
         {"threshold", r.threshold}});
  }
}

// Positions where the gyroscope was not still, turns within still positions, and no validation.
void GyroStillFindings(const GyroCalibration& g, std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  std::string turning;
  for (std::size_t i = 0; i < g.still_spans.size(); ++i) {
    if (g.still_spans[i].still) continue;
    turning += Format("%s%zu (%.3g deg)", turning.empty() ? "" : ", ", i + 1,
                      g.still_spans[i].turned_outside_deg);
  }
  if (!turning.empty()) {
    AddFinding(
        &out, "gyro_position_turning", Severity::kWarning,
        Format("the gyroscope did not stand still in position %s while the accelerometer was "
               "still (it turned about the vertical, which the accelerometer cannot see, or its "
               "rate there is off the offset the other positions agree on): no still rate was "
               "taken from it, and the turns on either side of it were integrated as one; hold "
               "the unit still in every position",
               turning.c_str()),
        {});
  }
  std::string turned;
  double most = 0;
  for (std::size_t i = 0; i < g.still_spans.size(); ++i) {
    if (!g.still_spans[i].still) continue;
    const double angle = g.still_spans[i].turned_outside_deg;
    if (!(angle > kGyroTurnedInStillNote_deg)) continue;
    turned += Format("%s%zu (%.3g deg)", turned.empty() ? "" : ", ", i + 1, angle);
    most = std::max(most, angle);
  }
  if (!turned.empty()) {
    AddFinding(
        &out, "gyro_turned_in_still", Severity::kNote,
        Format("the gyroscope turned while the accelerometer was still, in position %s: a turn "
               "about the vertical, which the accelerometer cannot see, or the gyro's readings "
               "lagging or leading the accelerometer's; those samples were integrated with the "
               "neighbouring turns, not averaged into the still rates",
               turned.c_str()),
        {{"largest_deg", most}});
  }
  if (!std::isfinite(g.heldout_rms_deg)) {
    AddFinding(&out, "gyro_not_validated", Severity::kNote,
               "the gyroscope's rotations were not held out one by one (validation turned off): no "
               "held-out error");
  }
}

// Scales far from the declared unit's, and the lag behind the accelerometer.
void GyroUnitAndLagFindings(const GyroCalibration& g, std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  if (const std::optional<double> nominal = RawPerRadPerSecond(g.unit)) {
    Vec3 scale;
    for (int i = 0; i < 3; ++i) scale(i) = g.params.K.row(i).norm() / *nominal;
    if (!((scale.array() - 1).abs() <= kGyroUnitScaleTolerance).all()) {
      const std::string unit(ToString(g.unit));
      AddFinding(
          &out, "gyro_unit_scale", Severity::kWarning,
          Format("the gyroscope's scales are %.3g, %.3g and %.3g times its declared unit %s "
                 "(a MEMS gyro's lie within a few percent): its readings were converted with "
                 "another range setting than the sensor's, or are in another unit; the "
                 "calibration maps them as they are",
                 scale(0), scale(1), scale(2), unit.c_str()),
          {{"scale_x", scale(0)}, {"scale_y", scale(1)}, {"scale_z", scale(2)}});
    }
  }
  if (const std::optional<GyroTimeOffset>& lag = g.time_offset) {
    const bool beyond =
        std::abs(lag->lag_s) > 3 * lag->std_s && std::abs(lag->lag_s) > 0.5 * lag->step_s;
    if (lag->at_limit) {
      // Failed when the rotations miss by more than the misfit's 2° too: the lag is more than
      // the still spans absorbed (a gyro 2 s early in 3 s stills: K_g 80 % low, 4.7° RMS, its
      // noise inflated 50 times, so that the misfit's ratio passed).
      const bool failed = g.rms_deg > kGyroMisfitFailure_deg;
      AddFinding(
          &out, "gyro_time_offset", failed ? Severity::kFailure : Severity::kWarning,
          Format(
              "the gyroscope's readings and the accelerometer's align best at the edge of the "
              "+-0.5 s searched (the gyro %s by at least %.3g ms), or do not correlate: the "
              "still positions may hold the gyro's turns%s; check that the two streams are of "
              "one sensor and on one clock",
              lag->lag_s >= 0 ? "late" : "early", std::abs(lag->lag_s) * 1e3,
              failed ? Format(", and the rotations miss by %.3g deg RMS", g.rms_deg).c_str() : ""),
          {{"lag_s", lag->lag_s}, {"rms_deg", g.rms_deg}});
    } else if (beyond) {
      AddFinding(
          &out, "gyro_time_offset", Severity::kNote,
          Format("the gyroscope's readings %s the accelerometer's by %.3g +- %.2g ms (the shift "
                 "that best aligns its rates with the accelerometer's tilting over the %zu turns): "
                 "each turn is integrated where the gyro turned, so the calibration holds; a "
                 "filter fusing the two streams needs that lag",
                 lag->lag_s >= 0 ? "lag" : "lead", std::abs(lag->lag_s) * 1e3, lag->std_s * 1e3,
                 lag->turns),
          {{"lag_s", lag->lag_s}, {"std_s", lag->std_s}});
    }
  }
}

}  // namespace

std::vector<Finding> GyroFindings(const GyroCalibration& g) {
  std::vector<Finding> out;
  GyroFitFindings(g, &out);
  GyroUnitAndLagFindings(g, &out);
  GyroStillFindings(g, &out);
  return out;
}

}  // namespace accelcal
