// A calibration checked on a new recording (verify.hpp).
#include "accelcal/verify.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "accelcal/calibration_types.hpp"
#include "accelcal/error.hpp"
#include "accelcal/position_noise.hpp"
#include "analysis/gyro_data.hpp"
#include "core/median.hpp"
#include "core/text_format.hpp"
#include "solvers/gyro_fit.hpp"
#include "statistics/student_t.hpp"

namespace accelcal {

namespace {

// ∂μ/∂θ at f, in the slots' order: K(r, c) moves row r by f_c, b_r by 1, k2_r by f_r².
Eigen::MatrixXd ModelJacobian(const std::vector<ParameterSlot>& slots, const Vec3& f) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, static_cast<Eigen::Index>(slots.size()));
  for (std::size_t s = 0; s < slots.size(); ++s) {
    J(slots[s].row, static_cast<Eigen::Index>(s)) = SlotRegressor(slots[s], f);
  }
  return J;
}

// The parameters position k is judged with: θ(T_k), its temperature held to the fitted range,
// for a calibration over temperature (with ΔT = T_k − T_ref in `dT`); else the calibration's.
ModelParameters ParametersAt(const VerifiedCalibration& cal, const Position& position,
                             std::size_t k, double* dT = nullptr) {
  if (!cal.thermal) return cal.params;
  if (!position.temperature_c) {
    throw DataError("position " + std::to_string(k + 1) +
                    " has no temperature, which the calibration's parameters follow");
  }
  const double t =
      std::clamp(*position.temperature_c, cal.thermal_range_c.first, cal.thermal_range_c.second);
  if (dT != nullptr) *dT = t - cal.thermal->t_ref_c;
  return cal.thermal->At(t);
}

// The calibration's flat vector θ: its model's slots, or over temperature the thermal slots, each
// the model slot it moves (`model_column`) times ΔT^degree.
struct FlatSlots {
  std::vector<ParameterSlot> slots;  // the model's, in its frame
  std::vector<ThermalSlot> thermal;  // empty: constant over temperature
  std::vector<Eigen::Index> model_column;
  Eigen::Index size() const {
    return static_cast<Eigen::Index>(thermal.empty() ? slots.size() : thermal.size());
  }
};
FlatSlots FlatSlotsOf(const VerifiedCalibration& cal) {
  FlatSlots out;
  out.slots = ParameterSlots(cal.model, cal.frame);
  if (!cal.thermal) return out;
  if (cal.frame != Frame::kXFirst) {
    throw std::invalid_argument("VerifyCalibration: a thermal model is in the x-first frame");
  }
  out.thermal = ThermalSlots(cal.model, cal.thermal->degrees);
  for (const ThermalSlot& t : out.thermal) {
    Eigen::Index column = 0;
    while (out.slots[static_cast<std::size_t>(column)].name != t.slot.name) ++column;
    out.model_column.push_back(column);
  }
  return out;
}

// ∂f/∂θ (3 x P) of the specific force f that `params` (θ at ΔT = `dT`) give a reading at f:
// f = μ⁻¹(p), so ∂f/∂θ = −J⁻¹ ∂μ/∂θ, J = K + 2 diag(k2 ∘ f), mapped to the flat slots.
Eigen::MatrixXd ForceSensitivity(const FlatSlots& s, const ModelParameters& params, const Vec3& f,
                                 double dT) {
  Mat33 J = params.K;
  for (int i = 0; i < 3; ++i) J(i, i) += 2 * params.k2(i) * f(i);
  const Eigen::MatrixXd model = -(J.inverse() * ModelJacobian(s.slots, f));
  if (s.thermal.empty()) return model;
  Eigen::MatrixXd out(3, s.size());
  for (Eigen::Index j = 0; j < s.size(); ++j) {
    const std::size_t i = static_cast<std::size_t>(j);
    out.col(j) = model.col(s.model_column[i]) * std::pow(dT, s.thermal[i].degree);
  }
  return out;
}

void CheckOptions(const VerifyOptions& options) {
  if (!(options.significance > 0 && options.significance < 1) || !(options.position_z > 0) ||
      !(options.untested_sigmas > 0)) {
    throw std::invalid_argument(
        "VerifyCalibration: the significance must lie in (0, 1), position_z and untested_sigmas "
        "be positive");
  }
}

// The positions furthest off, named 1-based as the files and the tool count them.
std::string Furthest(std::vector<std::size_t> off, const std::vector<double>& z,
                     const std::function<std::string(std::size_t)>& name) {
  std::sort(off.begin(), off.end(),
            [&](std::size_t a, std::size_t b) { return std::abs(z[a]) > std::abs(z[b]); });
  if (off.size() > 5) off.resize(5);
  std::string named;
  for (const std::size_t k : off) {
    named += (named.empty() ? "" : ", ") + name(k) + internal::Format(" (z = %+.1f)", z[k]);
  }
  return named;
}

// The noncentrality λ an error must add to χ²'s mean for the test at `significance` with `dof`
// degrees of freedom to notice it in 9 logs of 10: the noncentral χ² has mean n + λ and variance
// 2 (n + 2λ), and its mean less 1.28 of its standard deviations reaches the threshold T =
// χ²_{1−α}(n) when λ = T − n + 1.28 √(2 (n + 2λ)), solved by fixed-point steps (a contraction:
// the root's slope is below 1).
double NoticedNoncentrality(double significance, int dof) {
  const auto n = static_cast<double>(dof);
  const double T = internal::ChiSquareQuantile(significance, n);
  double q = T - n;
  for (int step = 0; step < 60; ++step) q = T - n + 1.2816 * std::sqrt(2 * (n + 2 * q));
  return q;
}

constexpr double kRadToDeg = 180 / 3.14159265358979323846;

// The accelerometer's calibration measures each position's gravity direction c_k, uncertain by
// its parameters': ∂δ_k/∂θ = Eᵀ (I − c cᵀ) / |f| ∂f/∂θ in c_k's tangent coordinates (TangentBasis
// E), carried into the turns (`sensitivity`, 2 x P per position, when wanted). DataError for a
// position the model cannot invert.
CalibrationResult GravityDirections(const VerifiedCalibration& accel, const FlatSlots& flat,
                                    const std::vector<Position>& positions,
                                    std::vector<Eigen::MatrixXd>* sensitivity) {
  CalibrationResult accel_cal;
  accel_cal.params = accel.params;
  accel_cal.gravity = accel.gravity;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    double dT = 0;
    const ModelParameters at_k = ParametersAt(accel, positions[k], k, &dT);
    const std::optional<Vec3> f = SpecificForce(at_k, positions[k].mean);
    if (!f || !(f->norm() > 0)) {
      throw DataError("still position " + std::to_string(k + 1) +
                      " reads outside the range the accelerometer's model can invert");
    }
    const Vec3 c = f->normalized();
    accel_cal.directions.push_back(c);
    if (sensitivity) {
      const Mat33 project = (Mat33::Identity() - c * c.transpose()) / f->norm();
      sensitivity->push_back(internal::TangentBasis(c).transpose() * project *
                             ForceSensitivity(flat, at_k, *f, dT));
    }
  }
  return accel_cal;
}

// Why the gyroscope's verification fails, or "": beyond any statistics (a prediction too loose to
// verify anything, a turn far off, a bias that moved further than any gyro's turn-on bias does),
// then the statistic and the turns furthest off. `z`: each turn's.
std::string GyroFailureReason(const GyroVerification& out, const VerifiedGyroscope& gyro,
                              const std::vector<double>& z, std::size_t K,
                              const VerifyOptions& options) {
  std::string reason;
  const double bias_change_deg_s =
      (gyro.params.K.inverse() * out.bias_change_raw).norm() * kRadToDeg;
  double worst_turn = 0;
  for (const VerifiedTurn& t : out.turns) worst_turn = std::max(worst_turn, t.error_deg);
  if (!std::isfinite(out.chi2) || !std::isfinite(out.rms_predicted_deg)) {
    reason =
        "the turns' statistic is not finite (the calibration's covariance or turn scatter ratio "
        "is beyond what arithmetic holds)";
  } else if (out.rms_predicted_deg > kMaxPredictedTurnDeg) {
    reason = internal::Format(
        "the calibration predicts turn errors of %.3g deg RMS (its covariance, its turn scatter "
        "ratio): beyond %g deg it verifies nothing",
        out.rms_predicted_deg, kMaxPredictedTurnDeg);
  } else if (!(bias_change_deg_s < kMaxBiasChangeDegS)) {
    reason = internal::Format(
        "the session's bias is %.3g deg/s from the calibration's (beyond %g deg/s no gyro's "
        "turn-on bias moves): is the gyroscope's log in the calibration's raw unit, and from "
        "this sensor?",
        bias_change_deg_s, kMaxBiasChangeDegS);
  } else if (worst_turn > kMaxTurnErrorDeg) {
    reason = internal::Format(
        "a turn is off by %.3g deg (beyond %g deg a calibrated gyroscope does not err): is the "
        "gyroscope's log in the calibration's raw unit, and from this sensor?",
        worst_turn, kMaxTurnErrorDeg);
  } else if (out.p_value < options.significance) {
    reason = internal::Format(
        "the turns' rotations and the still rates are further from what the gyroscope's "
        "calibration predicts than its noise and covariance allow: chi2 = %.4g for %d (the %zu "
        "turns' %.4g for %d, the still rates' %.4g for %d; p = %.2g < %.2g)",
        out.chi2, out.dof, K, out.turns_chi2, out.turns_dof, out.stills_chi2, out.stills_dof,
        out.p_value, options.significance);
    const std::string named = Furthest(out.off_turns, z, [&](std::size_t k) {
      return internal::Format("the turn %zu-%zu", out.turns[k].from + 1, out.turns[k].to + 1);
    });
    if (!named.empty()) reason += "; furthest off: " + named;
  }
  return reason;
}

// Why the accelerometer's verification fails, or "": the statistic, then the positions furthest
// off (1-based, as the files and the tool count them), and a hint when |f| is far from g.
std::string FailureReason(const Verification& out, const VerifiedCalibration& cal,
                          const std::vector<std::size_t>& outside,
                          const std::vector<double>& ratios, const VerifyOptions& options) {
  const std::size_t N = out.positions.size();
  std::string reason;
  std::vector<double> z;
  for (const VerifiedPosition& p : out.positions) z.push_back(p.z);
  const std::string named = Furthest(
      out.off_positions, z, [](std::size_t k) { return "position " + std::to_string(k + 1); });
  if (!std::isfinite(out.chi2) || !std::isfinite(out.rms_predicted)) {
    reason =
        "the statistic is not finite (the calibration's covariance or noise is beyond what "
        "arithmetic holds)";
  } else if (out.rms_predicted > kMaxPredictedNormError * cal.gravity) {
    reason = internal::Format(
        "the calibration predicts errors of |f| - g of %.3g RMS (%.3g of g: its covariance, its "
        "noise): beyond %g of g it verifies nothing",
        out.rms_predicted, out.rms_predicted / cal.gravity, kMaxPredictedNormError);
  } else if (!outside.empty()) {
    reason = internal::Format(
        "%zu of %zu positions read outside the range the model can invert (the first: position "
        "%zu)",
        outside.size(), N, outside.front() + 1);
  } else if (out.p_value < options.significance) {
    reason = internal::Format(
        "the errors |f| - g are larger than the calibration predicts: chi2 = %.4g for %d "
        "positions (p = %.2g < %.2g)",
        out.chi2, out.dof, out.p_value, options.significance);
    if (!named.empty()) reason += "; furthest off: " + named;
  }
  if (!reason.empty() && !ratios.empty()) {
    const double ratio = internal::Median(ratios);
    if (std::abs(ratio - 1) > 0.1) {
      reason += internal::Format(
          "; |f| is %.3g times g on the median position: is the log in the calibration's raw "
          "unit, and from this sensor?",
          ratio);
    }
  }
  return reason;
}

}  // namespace

GyroVerification VerifyGyroscope(const VerifiedCalibration& accel, const VerifiedGyroscope& gyro,
                                 const RawLog& accel_log, const RawLog& gyro_log,
                                 const std::vector<Position>& positions,
                                 const VerifyOptions& options) {
  CheckOptions(options);
  if (positions.size() < 2) {
    throw DataError(
        "the gyroscope is verified on the turns between still positions, and the log has " +
        std::to_string(positions.size()) + " still position");
  }
  const FlatSlots flat = FlatSlotsOf(accel);
  const bool accel_covariance = accel.covariance.rows() == flat.size() && flat.size() > 0;
  std::vector<Eigen::MatrixXd> direction_sensitivity;  // 2 x P per position
  const CalibrationResult accel_cal = GravityDirections(
      accel, flat, positions, accel_covariance ? &direction_sensitivity : nullptr);
  internal::Built built = internal::BuildData(accel_log, gyro_log, positions, accel_cal, {});
  internal::GyroFitData& data = built.data;
  data.model = gyro.model;
  GyroVerification out;
  GyroParameters params = gyro.params;
  const std::vector<GyroParameterSlot>& slots = GyroParameterSlots(gyro.model);
  const auto P = static_cast<Eigen::Index>(slots.size());
  if (gyro.covariance.size() > 0 && (gyro.covariance.rows() != P || gyro.covariance.cols() != P)) {
    throw std::invalid_argument("VerifyGyroscope: the covariance is not P x P");
  }
  // The session's bias, per axis the still positions' mean rates less G f weighted by their
  // noise (their samples' σ/√n times the calibration's still scatter ratio), and its variance.
  const double s2_still = std::pow(std::max(1.0, gyro.still_scatter_ratio), 2);
  const std::size_t Mn = data.stills.size();
  Vec3 weight_sum = Vec3::Zero(), sum = Vec3::Zero();
  // Per axis a: Σ w_ia f_i (Eigen's vectors start uninitialised: zeroed here).
  std::array<Vec3, 3> f_weighted = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  for (const internal::GyroStill& still : data.stills) {
    const Vec3 w = (s2_still * still.sigma_mean_raw.cwiseAbs2()).cwiseInverse();
    weight_sum += w;
    sum += w.cwiseProduct(still.mean_raw - gyro.params.G * still.f);
    for (int a = 0; a < 3; ++a) f_weighted[std::size_t(a)] += w(a) * still.f;
  }
  params.bias = sum.cwiseQuotient(weight_sum);
  out.session_bias_raw = params.bias;
  out.bias_change_raw = params.bias - gyro.params.bias;
  // The still rates about it: each component's variance its noise plus G's uncertainty along
  // its centred force (∂r_ia/∂G_ab = −(f_ib − f̄_b), f̄ the weighted mean of its axis).
  Eigen::MatrixXd sigma_G = Eigen::MatrixXd::Zero(P, P);
  if (gyro.covariance.size() > 0) sigma_G = gyro.covariance;
  std::vector<double> still_information(std::size_t(P), 0.0);
  for (const internal::GyroStill& still : data.stills) {
    const Vec3 r = still.mean_raw - params.bias - gyro.params.G * still.f;
    for (int a = 0; a < 3; ++a) {
      const Vec3 centred = still.f - f_weighted[std::size_t(a)] / weight_sum(a);
      Eigen::RowVectorXd d = Eigen::RowVectorXd::Zero(P);
      for (Eigen::Index i = 0; i < P; ++i) {
        const GyroParameterSlot& slot = slots[std::size_t(i)];
        if (slot.group == GyroParameterGroup::kG && slot.row == a) d(i) = -centred(slot.col);
      }
      const double noise = s2_still * still.sigma_mean_raw(a) * still.sigma_mean_raw(a);
      const double variance = noise + double(d * sigma_G * d.transpose());
      out.stills_chi2 += r(a) * r(a) / variance;
      for (Eigen::Index i = 0; i < P; ++i) still_information[std::size_t(i)] += d(i) * d(i) / noise;
    }
  }
  out.stills_dof = static_cast<int>(3 * (Mn - 1));
  // The parameters' covariance with the bias's part the session bias' own.
  Eigen::MatrixXd sigma = sigma_G;
  for (Eigen::Index i = 0; i < P; ++i) {
    if (slots[std::size_t(i)].group != GyroParameterGroup::kBias) continue;
    sigma.row(i).setZero();
    sigma.col(i).setZero();
    sigma(i, i) = 1 / weight_sum(slots[std::size_t(i)].row);
  }
  data.weights = internal::WeighMotions(data, params);
  const double s2 = std::pow(std::max(1.0, gyro.rotation_scatter_ratio), 2);
  const std::size_t K = data.motions.size();
  const auto rows = static_cast<Eigen::Index>(2 * K);
  Eigen::MatrixXd A(rows, P);
  // The turns' residuals' sensitivity to the accelerometer's parameters, through the directions.
  Eigen::MatrixXd A_accel = Eigen::MatrixXd::Zero(rows, accel_covariance ? flat.size() : 0);
  Eigen::VectorXd r(rows);
  std::vector<double> z;
  double sum_e2 = 0, sum_p2 = 0;
  for (std::size_t k = 0; k < K; ++k) {
    const internal::GyroMotion& m = data.motions[k];
    Eigen::MatrixXd J;
    Eigen::Matrix2d J_from, J_to;
    const Eigen::Vector2d r_k =
        internal::MotionResidual(data, m, data.weights[k], params, data.directions[m.from],
                                 data.directions[m.to], &J, &J_from, &J_to);
    const auto row = static_cast<Eigen::Index>(2 * k);
    A.middleRows(row, 2) = J;
    r.segment(row, 2) = r_k;
    Eigen::Matrix2d C_k = s2 * Eigen::Matrix2d::Identity() + J * sigma * J.transpose();
    if (accel_covariance) {
      A_accel.middleRows(row, 2) =
          J_from * direction_sensitivity[m.from] + J_to * direction_sensitivity[m.to];
      C_k += A_accel.middleRows(row, 2) * accel.covariance * A_accel.middleRows(row, 2).transpose();
    }
    const Eigen::Matrix2d L_inverse = data.weights[k].L.inverse();
    VerifiedTurn turn;
    turn.from = m.from;
    turn.to = m.to;
    turn.duration_s = built.rotations[k].duration_s;  // the turn proper, between its still spans
    turn.error_deg = internal::MotionAngleError(data, m, params) * kRadToDeg;
    turn.predicted_deg = std::sqrt((L_inverse * C_k * L_inverse.transpose()).trace()) * kRadToDeg;
    turn.z = std::sqrt(r_k.dot(C_k.ldlt().solve(r_k)));
    sum_e2 += turn.error_deg * turn.error_deg;
    sum_p2 += turn.predicted_deg * turn.predicted_deg;
    z.push_back(turn.z);
    if (turn.z > options.position_z) out.off_turns.push_back(k);
    out.turns.push_back(turn);
  }
  if (K > 0) {
    Eigen::MatrixXd C = s2 * Eigen::MatrixXd::Identity(rows, rows) + A * sigma * A.transpose();
    if (accel_covariance) C += A_accel * accel.covariance * A_accel.transpose();
    out.turns_chi2 = r.dot(C.ldlt().solve(r));
    out.turns_dof = static_cast<int>(rows);
    out.chi2 = out.turns_chi2 + out.stills_chi2;
    out.dof = out.turns_dof + out.stills_dof;
    out.p_value = internal::ChiSquareSurvival(out.chi2, out.dof);
    out.rms_error_deg = std::sqrt(sum_e2 / static_cast<double>(K));
    out.rms_predicted_deg = std::sqrt(sum_p2 / static_cast<double>(K));
    // What the turns and stills can see of K_g and G (as the accelerometer's positions).
    const double q = NoticedNoncentrality(options.significance, out.dof);
    for (Eigen::Index i = 0; i < P; ++i) {
      if (slots[std::size_t(i)].group == GyroParameterGroup::kBias) continue;
      VerifiedParameter v;
      v.name = std::string(slots[std::size_t(i)].name);
      const double information = A.col(i).squaredNorm() / s2 + still_information[std::size_t(i)];
      v.detectable =
          information > 0 ? std::sqrt(q / information) : std::numeric_limits<double>::infinity();
      v.sigma = gyro.covariance.size() > 0 ? std::sqrt(std::max(0.0, gyro.covariance(i, i))) : 0.0;
      if (!(v.detectable <= options.untested_sigmas * v.sigma)) out.untested.push_back(v.name);
      out.parameters.push_back(v);
    }
  }
  out.reason = GyroFailureReason(out, gyro, z, K, options);
  out.passed = out.reason.empty();
  return out;
}

Verification VerifyCalibration(const VerifiedCalibration& cal, const RawLog& log,
                               const std::vector<Position>& positions,
                               const VerifyOptions& options) {
  CheckOptions(options);
  if (positions.empty()) throw std::invalid_argument("VerifyCalibration: no positions");
  if (!(cal.gravity > 0) || !std::isfinite(cal.gravity) || !(cal.misfit_sigma_raw >= 0)) {
    throw std::invalid_argument(
        "VerifyCalibration: gravity must be positive and the misfit not negative");
  }
  const FlatSlots flat = FlatSlotsOf(cal);
  const Eigen::Index P = flat.size();
  const bool with_covariance = cal.covariance.size() > 0;
  if (with_covariance && (cal.covariance.rows() != P || cal.covariance.cols() != P)) {
    throw std::invalid_argument("VerifyCalibration: the covariance is not P x P");
  }
  Verification out;
  const std::size_t N = positions.size();
  std::vector<std::size_t> used;  // positions the model could invert
  Eigen::MatrixXd A(static_cast<Eigen::Index>(N), P);
  Eigen::VectorXd e(static_cast<Eigen::Index>(N)), noise(static_cast<Eigen::Index>(N));
  std::vector<std::size_t> outside;
  std::vector<double> ratios;  // |f| / g
  // The sensor's noise is the same in every position (position_noise.hpp): pooled over them. One
  // position's batches alone made 2 correct calibrations in 240 fail.
  Vec3 pooled;
  {
    std::vector<Vec3> variances;
    for (const Position& position : positions) {
      if (!position.interval) {
        throw std::invalid_argument("VerifyCalibration: a position without its interval");
      }
      variances.push_back(PositionMeanVariance(log, position));
    }
    pooled = PoolPositionNoise(positions, variances).per_sample_variance;
  }
  for (std::size_t k = 0; k < N; ++k) {
    const Position& position = positions[k];  // its interval checked by the pooling above
    VerifiedPosition v;
    v.mean_raw = position.mean;
    v.samples = position.samples;
    v.t_begin_s = position.interval->t_begin_s;
    v.t_end_s = position.interval->t_end_s;
    double dT = 0;
    const ModelParameters params = ParametersAt(cal, position, k, &dT);
    if (cal.thermal) v.temperature_c = *position.temperature_c;
    const std::optional<Vec3> f = SpecificForce(params, position.mean);
    if (!f || !(f->norm() > 0)) {
      v.error = v.sigma = v.z = std::numeric_limits<double>::quiet_NaN();
      outside.push_back(k);
      out.positions.push_back(v);
      continue;
    }
    const double norm = f->norm();
    ratios.push_back(norm / cal.gravity);
    Mat33 J = params.K;
    for (int i = 0; i < 3; ++i) J(i, i) += 2 * params.k2(i) * (*f)(i);
    // g = uᵀ J⁻¹: how |f| moves with the reading.
    const Eigen::RowVector3d g = (f->transpose() / norm) * J.inverse();
    const auto row = static_cast<Eigen::Index>(used.size());
    // ∂|f|/∂θ = uᵀ ∂f/∂θ.
    A.row(row) = (f->transpose() / norm) * ForceSensitivity(flat, params, *f, dT);
    const Vec3 mean_variance = pooled / static_cast<double>(position.interval->count());
    const double noise2 = g.cwiseProduct(g).dot(mean_variance);
    const double misfit2 = g.squaredNorm() * cal.misfit_sigma_raw * cal.misfit_sigma_raw;
    const double parameters2 =
        with_covariance ? double(A.row(row) * cal.covariance * A.row(row).transpose()) : 0.0;
    v.error = norm - cal.gravity;
    v.sigma_noise = std::sqrt(noise2);
    v.sigma_misfit = std::sqrt(misfit2);
    v.sigma_parameters = std::sqrt(std::max(0.0, parameters2));
    // Floored at a relative 1e-9 of g: a sensor quantised below its noise can hold a reading
    // constant, and a σ of 0 would make any round-off a failure.
    const double floor2 = std::pow(1e-9 * cal.gravity, 2);
    v.sigma = std::sqrt(std::max(floor2, noise2 + misfit2 + parameters2));
    v.z = v.error / v.sigma;
    e(row) = v.error;
    noise(row) = std::max(floor2, noise2 + misfit2);
    used.push_back(k);
    out.positions.push_back(v);
  }
  const auto n = static_cast<Eigen::Index>(used.size());
  double sum_e2 = 0, sum_s2 = 0;
  for (const std::size_t k : used) {
    sum_e2 += out.positions[k].error * out.positions[k].error;
    sum_s2 += out.positions[k].sigma * out.positions[k].sigma;
    if (std::abs(out.positions[k].z) > options.position_z) out.off_positions.push_back(k);
  }
  // What the log can see: an error δ in parameter i alone adds λ = δ² F_ii to χ²'s mean (F =
  // Aᵀ N⁻¹ A, the information of these positions), noticed from NoticedNoncentrality on.
  if (n > 0) {
    const double q = NoticedNoncentrality(options.significance, static_cast<int>(n));
    for (Eigen::Index i = 0; i < P; ++i) {
      double information = 0;
      for (Eigen::Index k = 0; k < n; ++k) information += A(k, i) * A(k, i) / noise(k);
      VerifiedParameter v;
      v.name = cal.thermal ? ThermalSlotName(flat.thermal[std::size_t(i)])
                           : std::string(flat.slots[std::size_t(i)].name);
      v.detectable =
          information > 0 ? std::sqrt(q / information) : std::numeric_limits<double>::infinity();
      v.sigma = with_covariance ? std::sqrt(std::max(0.0, cal.covariance(i, i))) : 0.0;
      if (!(v.detectable <= options.untested_sigmas * v.sigma)) out.untested.push_back(v.name);
      out.parameters.push_back(v);
    }
  }
  if (n > 0) {
    out.rms_error = std::sqrt(sum_e2 / static_cast<double>(n));
    out.rms_predicted = std::sqrt(sum_s2 / static_cast<double>(n));
    Eigen::MatrixXd C = noise.head(n).asDiagonal();
    if (with_covariance) C += A.topRows(n) * cal.covariance * A.topRows(n).transpose();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(C);
    out.chi2 = e.head(n).dot(ldlt.solve(e.head(n)));
    out.dof = static_cast<int>(n);
    out.p_value = internal::ChiSquareSurvival(out.chi2, out.dof);
  }
  out.reason = FailureReason(out, cal, outside, ratios, options);
  out.passed = out.reason.empty();
  return out;
}

}  // namespace accelcal
