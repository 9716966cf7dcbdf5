// The gyroscope's calibration from a recording of still positions and turns
// (gyro_calibration.hpp).
#include "accelcal/gyro_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "accelcal/error.hpp"
#include "accelcal/model.hpp"
#include "analysis/gyro_data.hpp"
#include "analysis/gyro_thermal.hpp"
#include "analysis/gyro_time_offset.hpp"
#include "core/parallel.hpp"
#include "core/text_format.hpp"
#include "io/gyro_still_runs.hpp"
#include "solvers/gyro_fit.hpp"
#include "solvers/imu_joint_fit.hpp"
#include "statistics/rounding.hpp"
#include "statistics/student_t.hpp"

namespace accelcal {

std::string_view ToString(GyroUnit unit) { return NameOf(unit); }
std::string_view ToString(GyroEstimator estimator) { return NameOf(estimator); }

std::optional<double> RawPerRadPerSecond(GyroUnit unit) {
  if (unit == GyroUnit::kRadPerSecond) return 1.0;
  if (unit == GyroUnit::kDegPerSecond) return 180.0 / 3.14159265358979323846;
  return std::nullopt;
}

namespace {

using internal::GyroFitData;
using internal::GyroMotion;
using internal::GyroStill;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadToDeg = 180.0 / kPi;

using internal::AxisName;
using internal::Num;
using internal::SamplesOf;

/// A turn of more than this per sample step is integrated too coarsely (the trapezoidal rule's
/// error grows with the square of the angle per step).
constexpr double kMaxDegreesPerStep = 10.0;

// The turned angle per step and about each raw axis, with the start's bias and scale: the turn
// that is too fast for the rate, the axis never turned about.
void CheckExcitation(const GyroFitData& data, const internal::GyroFitData& /*unused*/,
                     const GyroParameters& start) {
  const double k = start.K.rowwise().norm().mean();  // the start's K_g = k P, P a mount
  Vec3 turned = Vec3::Zero();
  for (const GyroMotion& m : data.motions) {
    for (std::size_t s = 0; s + 1 < m.t_s.size(); ++s) {
      const double w = m.step_weight.empty() ? 1.0 : m.step_weight[s];
      const Vec3 step =
          0.5 * (m.raw[s] + m.raw[s + 1] - 2 * start.bias) / k * (w * (m.t_s[s + 1] - m.t_s[s]));
      turned += step.cwiseAbs();
      if (step.norm() * kRadToDeg > kMaxDegreesPerStep) {
        throw DataError("the turn from position " + std::to_string(m.from + 1) + " to " +
                        std::to_string(m.to + 1) +
                        " is too fast for the sample rate: " + Num(step.norm() * kRadToDeg, 3) +
                        "° in one sample step (at "
                        "most " +
                        Num(kMaxDegreesPerStep, 3) + "°), so its integration is not exact");
      }
    }
  }
  const double most = turned.maxCoeff();
  for (int a = 0; a < 3; ++a) {
    if (!(turned(a) >= 0.05 * most) || !(turned(a) * kRadToDeg >= 90)) {
      throw DataError("the gyroscope was hardly turned about its " + AxisName(a) + " axis (" +
                      Num(turned(a) * kRadToDeg, 3) + "° in all the turns, against " +
                      Num(most * kRadToDeg, 3) +
                      "° about the most turned axis): its scale "
                      "cannot be determined; turn the sensor about every axis between positions");
    }
  }
}

}  // namespace

using internal::BuildData;
using internal::Built;

namespace {

struct Solution {
  GyroParameters gyro;
  std::vector<Vec3> directions;
  std::optional<internal::ImuJointFit> joint;
  internal::LeastSquaresSummary summary;
};

// Residuals are whitened (1σ each): a step that changes none by more than 1e-6 σ, or F by a
// relative 1e-10, leaves the parameters within about 1e-5 of a standard error of the optimum;
// tighter tolerances only spend evaluations on steps that F's round-off rejects.
// Nearly every step is taken, so a trial is linearised at once (linearize_trials).
internal::LeastSquaresOptions FitOptions(int threads) {
  internal::LeastSquaresOptions ls;
  ls.max_iterations = 50;
  ls.step_tolerance = 1e-6;
  ls.function_tolerance = 1e-10;
  ls.threads = threads;
  ls.linearize_trials = true;
  ls.keep_blocks = true;  // the held-out fits and leverages at the solution evaluate nothing again
  return ls;
}

// The joint problem's data: every position's accelerometer mean weighted by the residual σ̂ of
// the accelerometer's own fit (its scatter about the fitted surface). The positions scatter by
// model error and drift more than by their samples' noise, and not in proportion to 1/√n: on the
// T265 recording, weights from each position's sample noise (times the scatter ratio) give
// 0.29° held out against 0.21° with σ̂.
internal::ImuJointData JointData(const GyroFitData& gyro, const std::vector<Position>& positions,
                                 const CalibrationResult& accel_cal) {
  if (!(accel_cal.residual_sigma > 0)) {
    throw DataError(
        "the accelerometer's calibration has no residual degrees of freedom: its "
        "noise, and so its weight beside the gyroscope's, is unknown");
  }
  internal::ImuJointData joint;
  joint.gyro = gyro;
  joint.accel_model = accel_cal.model;
  joint.frame = accel_cal.frame;
  joint.gravity = accel_cal.gravity;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    joint.accel_means.push_back(positions[k].mean);
    joint.accel_sigmas.push_back(Vec3::Constant(accel_cal.residual_sigma));
    joint.accel_used.push_back(!accel_cal.excluded(k));
  }
  return joint;
}

// A held-out fit that is not determined (LeaveOneBlockOut's NaN) or whose K_g is singular (the
// turn left out was the only one about an axis): its predictions are NaN, not an error.
bool Determined(const GyroParameters& gyro) {
  const double det = gyro.K.determinant();
  return std::isfinite(det) && det != 0 && gyro.bias.allFinite() && gyro.G.allFinite();
}

// Turn k under `gyro` and `directions`, from one integration of its rates.
struct TurnCheck {
  double error = 0;   // the angle [rad] between the direction it predicts for c_to and c_to
  double turned = 0;  // the angle of its rotation [rad]
  // ‖r‖² of its whitened residual (its weight, the turns' scatter ratio): under a fit without
  // it, about χ² with 2 degrees of freedom for a turn like the others.
  double chi2 = 0;
};

TurnCheck CheckTurn(const GyroFitData& data, std::size_t k, const GyroParameters& gyro,
                    const std::vector<Vec3>& directions) {
  if (!Determined(gyro)) return {std::nan(""), std::nan(""), std::nan("")};
  const GyroMotion& m = data.motions[k];
  const Mat33 R = IntegrateCalibratedRate(gyro, data.model, m.t_s, m.raw, m.f, data.rule, nullptr,
                                          nullptr, nullptr, m.weights());
  const Vec3 v = R.transpose() * directions[m.from];
  const Vec3& c = directions[m.to];
  return {std::atan2(v.cross(c).norm(), v.dot(c)), so3::Log(R).norm(),
          internal::RotationResidual(data.weights[k], R, directions[m.from], c).squaredNorm() /
              (data.motion_scale * data.motion_scale)};
}

// Scatter ratio sqrt(χ²/n) of the stills and of the turns under the sample noise (data's
// weights), at the two-stage fit whose summary kept its blocks: the stills', then the turns'.
std::pair<double, double> ScatterRatios(const GyroFitData& data,
                                        const internal::LeastSquaresSummary& solution) {
  const std::size_t stills = data.stills.size(), turns = data.motions.size();
  if (solution.block_residuals.size() != stills + turns) {
    throw std::logic_error("ScatterRatios: the fit's blocks were not kept");
  }
  double chi2_stills = 0, chi2_turns = 0;
  for (std::size_t k = 0; k < stills; ++k) {
    chi2_stills += solution.block_residuals[k].squaredNorm();
  }
  for (std::size_t k = 0; k < turns; ++k) {
    chi2_turns += solution.block_residuals[stills + k].squaredNorm();
  }
  return {data.still_scale * std::sqrt(chi2_stills / (3.0 * static_cast<double>(stills))),
          data.motion_scale * std::sqrt(chi2_turns / (2.0 * static_cast<double>(turns)))};
}

struct ModelFit {
  GyroModelKind kind;
  Solution solution;
  GyroFitData data;
  double still_ratio = 1, turn_ratio = 1, accel_ratio = 1;
  std::vector<double> heldout;       // per turn [rad], empty without validation
  std::vector<double> heldout_chi2;  // per turn: its whitened held-out residual, squared
  std::optional<internal::ImuJointData> joint_data;  // the joint estimator's problem
};

// The motions as the turns proper, from the last sample of one still span to the first of the
// next: their steps of weight 1 (a span's steps weigh less than 1: BuildData).
internal::GyroMotions WithoutSpans(const internal::GyroMotions& motions) {
  internal::GyroMotions out;
  for (const GyroMotion& m : motions) {
    std::size_t first = 0, last = m.step_weight.size();  // the turn's steps [first, last)
    while (first < last && m.step_weight[first] < 1) ++first;
    while (last > first && m.step_weight[last - 1] < 1) --last;
    GyroMotion turn;
    turn.from = m.from;
    turn.to = m.to;
    const auto begin = static_cast<std::ptrdiff_t>(first);
    const auto end = static_cast<std::ptrdiff_t>(m.step_weight.empty() ? m.t_s.size() : last + 1);
    turn.t_s.assign(m.t_s.begin() + begin, m.t_s.begin() + end);
    turn.raw.assign(m.raw.begin() + begin, m.raw.begin() + end);
    turn.f.assign(m.f.begin() + begin, m.f.begin() + end);
    out.push_back(std::move(turn));
  }
  return out;
}

void RequireConverged(const internal::LeastSquaresSummary& summary) {
  if (!summary.converged()) {
    throw NotConvergedError(
        "the gyroscope's fit did not converge (" + summary.termination_message +
        "): check that these are the gyroscope's rates, recorded through the accelerometer's "
        "positions");
  }
}

ModelFit FitModel(GyroFitData data, GyroModelKind kind, const std::vector<Position>& positions,
                  const CalibrationResult& accel_cal, const GyroCalibrationOptions& options,
                  const GyroParameters& start) {
  ModelFit out;
  out.kind = kind;
  data.model = kind;
  if (options.estimator == GyroEstimator::kImuTk) {
    // imu_tk's bias: the first still position's mean rate, held (its residual weighted 10¹²
    // times, the others' left out); K_g from the turns alone, each integrated from the last
    // sample of one still span to the first of the next (not from their mean orientations).
    // Its σ is that mean's (below).
    data.stills.resize(1);
    data.stills[0].sigma_mean_raw *= 1e-6;
    data.motions = WithoutSpans(data.motions);
    data.weights = internal::WeighMotions(data, start);
  }
  // The two-stage fit under the sample noise (data.weights, the turns' weights); each group's
  // scatter ratio there, and the fit again with each group's noise scaled by its ratio (when
  // above 1).
  const internal::GyroFit two = internal::FitGyro(data, start, FitOptions(options.threads));
  RequireConverged(two.summary);
  const auto [still_ratio, turn_ratio] = ScatterRatios(data, two.summary);
  out.still_ratio = still_ratio;
  out.turn_ratio = turn_ratio;
  data.still_scale = std::max(1.0, still_ratio);
  data.motion_scale = std::max(1.0, turn_ratio);
  Solution& s = out.solution;
  if (options.estimator == GyroEstimator::kJoint) {
    internal::ImuJointData joint = JointData(data, positions, accel_cal);
    internal::ImuJointFit fit =
        internal::FitImuJoint(joint, accel_cal.params, two.params, FitOptions(options.threads));
    RequireConverged(fit.summary);
    // Each group's scatter ratio again at the joint solution, R_G = √(χ²_G / r_G) with r_G the
    // group's redundancy (its rows less its leverage: the directions soak up much of the turns'
    // residuals, so χ²/n would understate their scatter), and the fit again with them, until
    // they settle within 10 % (at most 4 rounds): a ratio from r degrees of freedom has a
    // relative standard error of about 1/√(2r), 9 % for the 60 of a 38-position recording's
    // turns, so closer than that is noise. The accelerometer's is relative to the σ̂ of its own
    // fit.
    const std::vector<Vec3> accel_sigmas = joint.accel_sigmas;
    double accel_scale = 1;
    for (int round = 0; round < 4; ++round) {
      const internal::GroupCosts chi2 = internal::JointGroupCosts(joint, fit);
      const internal::GroupCosts redundancy = internal::JointGroupRedundancy(joint, fit);
      const auto ratio = [](double scale, double chi2_scaled, double r) {
        return r > 0 ? scale * std::sqrt(chi2_scaled / r) : scale;
      };
      out.accel_ratio = ratio(accel_scale, chi2.accel, redundancy.accel);
      out.still_ratio = ratio(data.still_scale, chi2.stills, redundancy.stills);
      out.turn_ratio = ratio(data.motion_scale, chi2.turns, redundancy.turns);
      const double a = std::max(1.0, out.accel_ratio), st = std::max(1.0, out.still_ratio),
                   tu = std::max(1.0, out.turn_ratio);
      if (std::abs(a / accel_scale - 1) <= 0.1 && std::abs(st / data.still_scale - 1) <= 0.1 &&
          std::abs(tu / data.motion_scale - 1) <= 0.1) {
        break;
      }
      accel_scale = a;
      data.still_scale = st;
      data.motion_scale = tu;
      joint.gyro.still_scale = st;
      joint.gyro.motion_scale = tu;
      for (std::size_t k = 0; k < accel_sigmas.size(); ++k) {
        joint.accel_sigmas[k] = accel_scale * accel_sigmas[k];
      }
      joint.gyro.directions = fit.directions;
      fit = internal::FitImuJoint(joint, fit.accel, fit.gyro, FitOptions(options.threads));
      RequireConverged(fit.summary);
    }
    if (options.validate && options.heldout_refits) {
      for (std::size_t k = 0; k < data.motions.size(); ++k) {
        internal::ImuJointData without = joint;
        without.gyro.motion_used.assign(data.motions.size(), true);
        without.gyro.motion_used[k] = false;
        const internal::ImuJointFit held =
            internal::FitImuJoint(without, fit.accel, fit.gyro, FitOptions(options.threads));
        RequireConverged(held.summary);
        const TurnCheck check = CheckTurn(data, k, held.gyro, held.directions);
        out.heldout.push_back(check.error);
        out.heldout_chi2.push_back(check.chi2);
      }
    } else if (options.validate) {
      for (const internal::ImuJointFit& held : internal::HeldOutMotionFits(joint, fit)) {
        const TurnCheck check = CheckTurn(data, out.heldout.size(), held.gyro, held.directions);
        out.heldout.push_back(check.error);
        out.heldout_chi2.push_back(check.chi2);
      }
    }
    s.gyro = fit.gyro;
    s.directions = fit.directions;
    s.summary = fit.summary;
    s.joint = std::move(fit);
    out.joint_data = joint;
  } else {
    internal::GyroFit fit = internal::FitGyro(data, two.params, FitOptions(options.threads));
    RequireConverged(fit.summary);
    if (options.validate && options.heldout_refits) {
      for (std::size_t k = 0; k < data.motions.size(); ++k) {
        GyroFitData without = data;
        without.motion_used.assign(data.motions.size(), true);
        without.motion_used[k] = false;
        const internal::GyroFit held =
            internal::FitGyro(without, fit.params, FitOptions(options.threads));
        RequireConverged(held.summary);
        const TurnCheck check = CheckTurn(data, k, held.params, data.directions);
        out.heldout.push_back(check.error);
        out.heldout_chi2.push_back(check.chi2);
      }
    } else if (options.validate) {
      for (const GyroParameters& held :
           internal::HeldOutMotionFits(data, fit.params, &fit.summary)) {
        const TurnCheck check = CheckTurn(data, out.heldout.size(), held, data.directions);
        out.heldout.push_back(check.error);
        out.heldout_chi2.push_back(check.chi2);
      }
    }
    s.gyro = fit.params;
    s.directions = data.directions;
    s.summary = std::move(fit.summary);
  }
  out.data = std::move(data);
  return out;
}

double RmsDeg(const std::vector<double>& rad) {
  double sum = 0;
  for (double e : rad) sum += e * e;
  return std::sqrt(sum / static_cast<double>(rad.size())) * kRadToDeg;
}

}  // namespace

bool SameTemperatureSensor(const std::string& a, const std::string& b) {
  const auto sensor = [](const std::string& s) { return s.substr(0, s.find(':')); };
  return sensor(a) == sensor(b);
}

// The chosen fit's checks: each turn's residual, held-out error and angle turned, the
// covariance (the accelerometer's too, when refitted jointly), and the angle the gyro turned in
// each position outside its still run.
void CheckFit(const RawLog& accel, const RawLog& gyro, const std::vector<Position>& positions,
              const CalibrationResult& accel_cal, const GyroCalibrationOptions& options,
              const Built& built, const ModelFit& f, GyroCalibration* out) {
  const bool imutk = options.estimator == GyroEstimator::kImuTk;
  std::vector<double> errors;
  for (std::size_t k = 0; k < f.data.motions.size(); ++k) {
    const TurnCheck check = CheckTurn(f.data, k, f.solution.gyro, f.solution.directions);
    errors.push_back(check.error);
    out->rotations[k].residual_deg = errors.back() * kRadToDeg;
    out->rotations[k].angle_deg = check.turned * kRadToDeg;
    if (!f.heldout.empty()) {
      // A turn that disagrees with the others (a bump during it, a slip of the hand): its held-out
      // χ²₂ beyond the level a turn like the others passes with probability 1 % / K (Bonferroni
      // over the K turns): P(χ²₂ > q) = exp(−q/2), so q > 2 ln(100 K).
      GyroRotation& r = out->rotations[k];
      r.heldout_deg = f.heldout[k] * kRadToDeg;
      r.statistic = f.heldout_chi2[k];
      r.threshold = 2 * std::log(100.0 * static_cast<double>(f.data.motions.size()));
      r.flagged = r.statistic > r.threshold;
    }
  }
  out->rms_deg = RmsDeg(errors);
  if (!f.heldout.empty()) out->heldout_rms_deg = RmsDeg(f.heldout);
  const internal::LeastSquaresSummary& sum = f.solution.summary;
  const int pa = f.solution.joint ? f.solution.joint->accel_parameters : 0;
  const int pg = NumGyroParameters(f.kind);
  if (sum.information.rows() > 0 && sum.degrees_of_freedom > 0) {
    const Eigen::MatrixXd C = sum.information.inverse() * std::max(1.0, sum.sigma2);
    out->covariance = C.block(pa, pa, pg, pg);
    if (f.solution.joint) {
      CalibrationResult a = accel_cal;
      a.params = f.solution.joint->accel;
      a.directions = f.solution.directions;
      for (std::size_t k = 0; k < a.residuals.size(); ++k) {
        a.residuals[k] =
            positions[k].mean - PredictRaw(a.params, Vec3(a.gravity * a.directions[k]));
      }
      a.covariance = C.block(0, 0, pa, pa);
      a.noise_source = "joint";  // σ̂ of the accelerometer's fit, beside the gyro's groups
      a.scatter_ratio = std::nan("");
      // The summary stays the accelerometer's own fit's (its cost is in raw², the joint fit's
      // is whitened: the gyroscope's summary).
      a.summary.initialization_note +=
          std::string(a.summary.initialization_note.empty() ? "" : "; ") +
          "refitted jointly with the gyroscope's rotations (see its solver)";
      // Held out as the accelerometer's own fit is: |f_k| − g of each position under the joint
      // fit without its reading (to first order, LeaveOneBlockOut).
      a.crossval_errors.clear();
      a.crossval_rms.reset();
      if (options.validate) {
        for (const internal::ImuJointFit& held :
             internal::HeldOutPositionFits(*f.joint_data, *f.solution.joint)) {
          const std::size_t k = a.crossval_errors.size();
          const std::optional<Vec3> force = SpecificForce(held.accel, positions[k].mean);
          a.crossval_errors.push_back(force ? force->norm() - a.gravity : std::nan(""));
        }
        a.crossval_rms = Rms(a.InFit(a.crossval_errors));
        a.crossval_note.clear();
      } else {
        a.crossval_note = "not validated";
      }
      out->accelerometer = std::move(a);
    }
  }
  if (imutk && out->covariance.size() > 0) {
    // The bias held at the first position's mean: its σ that mean's, K_g's σ given it.
    for (int a = 0; a < 3; ++a) {
      const int i = 4 * a + 3;  // bg_a in the linear model's order
      out->covariance.row(i).setZero();
      out->covariance.col(i).setZero();
      const double sigma = built.data.stills[0].sigma_mean_raw(a);
      out->covariance(i, i) = sigma * sigma;
    }
  }
  // The angle each turn turned through, unwrapped, and its σ from the parameters' covariance and
  // the rate noise of its samples (a check of the scale against a turn of known angle).
  for (std::size_t k = 0; k < f.data.motions.size(); ++k) {
    const GyroMotion& m = f.data.motions[k];
    const TurnedAngle turned =
        IntegrateTurnedAngle(f.solution.gyro, f.kind, m.t_s, m.raw, m.f, f.data.rule,
                             built.data.noise_sigma_raw, m.weights());
    double variance = turned.noise_variance_rad2;
    if (out->covariance.size() > 0) {
      variance += turned.gradient.dot(out->covariance * turned.gradient.transpose());
    }
    out->rotations[k].turned_deg = turned.angle_rad * kRadToDeg;
    out->rotations[k].turned_std_deg = std::sqrt(variance) * kRadToDeg;
  }
  // Where the gyro was still in each position, and the angle it turned outside that but inside
  // the accelerometer's still interval (a turn about the vertical, the ends of the turns the
  // accelerometer hardly sees, a lag of the gyro's stream); in a position it turned throughout,
  // the interval's mean rate and the angle turned over all of it.
  std::vector<const internal::GyroStill*> still_of(positions.size(), nullptr);
  for (const internal::GyroStill& s : built.data.stills) still_of[s.position] = &s;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const StaticInterval& iv = *positions[i].interval;
    const StaticInterval& run = built.still_runs[i];
    GyroStillSpan span;
    const Vec3 f0 = accel_cal.gravity * f.solution.directions[i];
    const auto turned_deg = [&](std::size_t a, std::size_t b) {
      const GyroMotion part = SamplesOf(accel, gyro, built.t, accel_cal.params, f0, a, b);
      return IntegrateTurnedAngle(f.solution.gyro, f.kind, part.t_s, part.raw, part.f, f.data.rule,
                                  built.data.noise_sigma_raw)
                 .angle_rad *
             kRadToDeg;
    };
    if (still_of[i] == nullptr) {
      span.still = false;
      span.first_sample = iv.begin;
      span.last_sample = iv.end - 1;
      for (std::size_t k = iv.begin; k < iv.end; ++k) span.mean_raw += gyro.samples[k];
      span.mean_raw /= static_cast<double>(iv.end - iv.begin);
      if (iv.end - iv.begin >= 2) span.turned_outside_deg = turned_deg(iv.begin, iv.end - 1);
      out->still_spans.push_back(span);
      continue;
    }
    span.first_sample = run.begin;
    span.last_sample = run.end - 1;
    span.mean_raw = still_of[i]->mean_raw;
    for (const auto& [a, b] :
         {std::pair{iv.begin, run.begin}, std::pair{run.end - 1, iv.end - 1}}) {
      if (b <= a) continue;
      span.turned_outside_deg += turned_deg(a, b);
    }
    out->still_spans.push_back(span);
  }
}

namespace {

// The gyroscope's offsets over temperature, from the still means of the rates as read, and in
// `corrected` every rate sample with them taken out at its temperature.
GyroThermal FitThermalOffsets(const RawLog& accel, const RawLog& raw_gyro,
                              const std::vector<Position>& positions,
                              const CalibrationResult& accel_cal,
                              const GyroCalibrationOptions& options,
                              const std::optional<GyroModelKind>& model, RawLog* corrected) {
  if (options.estimator == GyroEstimator::kJoint) {
    throw std::invalid_argument(
        "CalibrateGyro: the joint estimator refits the accelerometer's parameters as "
        "constants; with the offsets over temperature use the two-stage one");
  }
  const Built as_read = BuildData(accel, raw_gyro, positions, accel_cal, options);
  const std::vector<double> t_c = GyroSampleTemperatures(raw_gyro, accel);
  std::vector<double> position_t_c;
  for (const internal::GyroStill& still : as_read.data.stills) {
    const StaticInterval& run = as_read.still_runs[still.position];
    double sum = 0;
    for (std::size_t k = run.begin; k < run.end; ++k) sum += t_c[k];
    position_t_c.push_back(sum / static_cast<double>(run.end - run.begin));
  }
  GyroThermal thermal = internal::FitGyroThermal(as_read.data.stills, position_t_c,
                                                 *options.thermal, model != GyroModelKind::kLinear);
  thermal.temperature_source = GyroTemperatureSource(raw_gyro, accel);
  *corrected = raw_gyro;
  for (std::size_t k = 0; k < corrected->samples.size(); ++k) {
    corrected->samples[k] -= thermal.bias.OffsetChange(t_c[k]);
  }
  return thermal;
}

// The automatic choice between the linear model (fits[0]) and the g-sensitive one (fits[1]):
// the index of the one chosen, and in `reason` why.
std::size_t ChooseModel(const std::vector<ModelFit>& fits, std::string* reason) {
  // The paired comparison of the held-out errors, turn by turn (as the accelerometer's
  // automatic model choice): d_k = e_lin,k² − e_gs,k², g-sensitive when mean(d) exceeds
  // t_{n−1}(0.95) · sd(d)/√n.
  const std::size_t n = fits[0].heldout.size();
  double mean = 0, var = 0;
  for (std::size_t k = 0; k < n; ++k) {
    mean += fits[0].heldout[k] * fits[0].heldout[k] - fits[1].heldout[k] * fits[1].heldout[k];
  }
  mean /= static_cast<double>(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double d =
        fits[0].heldout[k] * fits[0].heldout[k] - fits[1].heldout[k] * fits[1].heldout[k];
    var += (d - mean) * (d - mean);
  }
  const double se = std::sqrt(var / static_cast<double>(n - 1) / static_cast<double>(n));
  const double threshold =
      internal::StudentTTwoSidedQuantile(0.10, static_cast<double>(n - 1)) * se;
  const std::size_t chosen = mean > threshold ? 1 : 0;
  *reason = internal::Format(
      "held-out RMS %.3g° (linear) against %.3g° (g-sensitive); the mean of the paired "
      "differences of squares %.3g deg² %s the threshold %.3g deg² (t · standard error)",
      RmsDeg(fits[0].heldout), RmsDeg(fits[1].heldout), mean * kRadToDeg * kRadToDeg,
      chosen == 1 ? "exceeds" : "does not exceed", threshold * kRadToDeg * kRadToDeg);
  return chosen;
}

}  // namespace

GyroCalibration CalibrateGyro(const RawLog& accel, const RawLog& raw_gyro,
                              const std::vector<Position>& positions,
                              const CalibrationResult& accel_cal,
                              const GyroCalibrationOptions& options) {
  if (auto why = options.Validate()) throw OptionError(*why);
  const bool imutk = options.estimator == GyroEstimator::kImuTk;
  const std::optional<GyroModelKind> model = imutk ? GyroModelKind::kLinear : options.model;
  CheckGyroClock(accel, raw_gyro);
  // The offsets over temperature first; then every rate sample with them taken out at its
  // temperature, and the calibration as without.
  RawLog corrected;
  std::optional<GyroThermal> thermal;
  if (options.thermal) {
    thermal = FitThermalOffsets(accel, raw_gyro, positions, accel_cal, options, model, &corrected);
  }
  const RawLog& gyro = options.thermal ? corrected : raw_gyro;
  Built built = BuildData(accel, gyro, positions, accel_cal, options);
  GyroFitData& data = built.data;
  const std::size_t needed = 6;
  if (data.motions.size() < needed) {
    throw DataError(std::to_string(data.motions.size()) +
                    " turns between still positions; the gyroscope's K_g (9 parameters, 2 from "
                    "each turn) needs at least " +
                    std::to_string(needed));
  }
  const std::optional<double> scale = RawPerRadPerSecond(options.unit);
  // A declared unit must agree with the angles turned: the closed-form scale (GyroStart) is
  // within 0.1 % of the fitted one on the Xsens recording and 2 % on the T265 one; a declared
  // scale from half to twice it is accepted, where a misread unit is a factor of 57 or more.
  const double turned_scale = internal::GyroStart(data, std::nullopt).K.row(0).norm();
  if (scale && !(*scale >= 0.5 * turned_scale && *scale <= 2 * turned_scale)) {
    throw DataError(internal::Format(
        "the rates read in %s turn the sensor %.3g times the angles the accelerometer sees "
        "between its positions: the gyroscope's unit is not %s (its readings are about %.4g "
        "per rad/s)",
        std::string(ToString(options.unit)).c_str(), turned_scale / *scale,
        std::string(ToString(options.unit)).c_str(), turned_scale));
  }
  // Within that, a declared unit more than 10 % from the turned angles' is no start (a fit
  // started 1.8 times off lands in another minimum, 87° RMS from the directions): the
  // closed-form scale is, and the diagnosis doubts the unit (gyro_unit_scale).
  const bool unit_agrees = scale && std::abs(*scale / turned_scale - 1) <= kGyroUnitScaleTolerance;
  const GyroParameters start = internal::GyroStart(data, unit_agrees ? scale : std::nullopt);
  // The turns' weights, once, at the start: its scale is within 0.1 % (Xsens) to 2 % (T265) of the
  // fitted one, so the propagated noise is within a few percent, and the turns' scatter ratio
  // sets their overall level anyway.
  data.weights = internal::WeighMotions(data, start);
  CheckExcitation(data, data, start);

  std::vector<ModelFit> fits;
  if (model) {
    fits.push_back(FitModel(data, *model, positions, accel_cal, options, start));
  } else {
    // Both models from the same start, side by side: a thread each when there are two, and the
    // rest of the threads asked for shared between them for the turns. Each fit is the same bits
    // on any count; an error is the linear model's first, as in turn.
    const GyroModelKind kinds[2] = {GyroModelKind::kLinear, GyroModelKind::kGSensitive};
    const int outer = internal::ThreadCount(options.threads, 2);
    GyroCalibrationOptions each = options;
    each.threads = std::max(1, internal::ThreadCount(options.threads, 1 << 20) / outer);
    std::vector<std::optional<ModelFit>> fitted(2);
    internal::ParallelFor(2, outer, [&](int i) {
      fitted[static_cast<std::size_t>(i)] =
          FitModel(data, kinds[i], positions, accel_cal, each, start);
    });
    for (std::optional<ModelFit>& f : fitted) fits.push_back(std::move(*f));
  }
  std::size_t chosen = 0;
  GyroCalibration result;
  if (model) {
    result.model_reason = imutk ? "imu_tk's method: no g-sensitivity" : "given";
  } else {
    chosen = ChooseModel(fits, &result.model_reason);
  }
  const ModelFit& f = fits[chosen];
  result.model = f.kind;
  result.estimator = options.estimator;
  result.unit = options.unit;
  if (options.latitude_deg) {
    result.latitude_deg = options.latitude_deg;
    result.earth_rate_vertical_rad_s = data.earth_rate_vertical;
    result.earth_rate_horizontal_rad_s =
        kEarthRate_rad_s * std::cos(*options.latitude_deg * kPi / 180);
  }
  result.params = f.solution.gyro;
  result.noise_sigma_raw = data.noise_sigma_raw;
  result.still_scatter_ratio = f.still_ratio;
  result.rotation_scatter_ratio = f.turn_ratio;
  result.accel_scatter_ratio = f.accel_ratio;
  result.rotations = built.rotations;
  // The lag estimate needs only the turns' samples and the chosen fit: on a thread of its own,
  // beside the checks of each turn and position below.
  std::optional<GyroTimeOffset> lag;
  const auto estimate_lag = [&] {
    std::vector<std::pair<std::size_t, std::size_t>> turns;
    for (const GyroRotation& r : built.rotations) turns.emplace_back(r.first_sample, r.last_sample);
    // The specific force of the accelerometer's own fit, as the turns were integrated with.
    lag = internal::EstimateGyroLag(accel, gyro, built.t, built.step_s, turns, accel_cal.params,
                                    f.solution.gyro);
  };
  internal::ParallelFor(2, internal::ThreadCount(options.threads, 2), [&](int task) {
    if (task == 1) {
      estimate_lag();
    } else {
      CheckFit(accel, gyro, positions, accel_cal, options, built, f, &result);
    }
  });
  result.time_offset = lag;
  result.thermal = std::move(thermal);
  const internal::LeastSquaresSummary& sum = f.solution.summary;
  result.summary.iterations = sum.iterations;
  result.summary.termination = sum.termination;
  result.summary.termination_message = sum.termination_message;
  result.summary.initial_cost = sum.initial_cost;
  result.summary.final_cost = sum.final_cost;

  return result;
}

}  // namespace accelcal
