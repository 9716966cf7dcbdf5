// A calibration checked on a new recording (verify.hpp).
#include "accelcal/verify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "core/median.hpp"
#include "core/text_format.hpp"
#include "statistics/student_t.hpp"

namespace accelcal {

namespace {

// Batches the mean's noise is measured over: 16 gives 15 degrees of freedom per axis, and
// batches of at least 8 samples (shorter ones would not hold a filtered sensor's correlation).
constexpr std::size_t kBatches = 16;
constexpr std::size_t kMinBatchSamples = 8;

// The covariance of a position's mean reading (diagonal, raw²): the scatter of its batch means
// over their count, or σ²/n for a position too short to batch or joined across a disturbance
// (its samples are not one run).
Vec3 MeanVariance(const RawLog& log, const Position& position) {
  const StaticInterval& in = *position.interval;
  const std::size_t n = in.end - in.begin;
  const Vec3 std = position.std.value_or(in.std);
  if (in.averaged > 0 || n < kBatches * kMinBatchSamples) {
    return std.cwiseProduct(std) / static_cast<double>(std::max<std::size_t>(1, in.count()));
  }
  const std::size_t size = n / kBatches;
  Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero();
  std::vector<Vec3> means(kBatches, Vec3::Zero());
  for (std::size_t b = 0; b < kBatches; ++b) {
    for (std::size_t i = 0; i < size; ++i) means[b] += log.samples[in.begin + b * size + i];
    means[b] /= static_cast<double>(size);
    sum += means[b];
  }
  const Vec3 mean = sum / static_cast<double>(kBatches);
  for (const Vec3& m : means) sum2 += (m - mean).cwiseProduct(m - mean);
  // The variance of one batch mean over the batches in the whole interval: var / kBatches.
  return sum2 / static_cast<double>((kBatches - 1) * kBatches);
}

// ∂μ/∂θ at f, in the slots' order: K(r, c) moves row r by f_c, b_r by 1, k2_r by f_r².
Eigen::MatrixXd ModelJacobian(const std::vector<ParameterSlot>& slots, const Vec3& f) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, static_cast<Eigen::Index>(slots.size()));
  for (std::size_t s = 0; s < slots.size(); ++s) {
    const ParameterSlot& slot = slots[s];
    const auto col = static_cast<Eigen::Index>(s);
    switch (slot.group) {
      case ParameterGroup::kK:
        J(slot.row, col) = f(slot.col);
        break;
      case ParameterGroup::kBias:
        J(slot.row, col) = 1;
        break;
      case ParameterGroup::kK2:
        J(slot.row, col) = f(slot.row) * f(slot.row);
        break;
    }
  }
  return J;
}

}  // namespace

Verification VerifyCalibration(const VerifiedCalibration& cal, const RawLog& log,
                               const std::vector<Position>& positions,
                               const VerifyOptions& options) {
  if (!(options.significance > 0 && options.significance < 1) || !(options.position_z > 0)) {
    throw std::invalid_argument(
        "VerifyCalibration: the significance must lie in (0, 1) and position_z be positive");
  }
  if (positions.empty()) throw std::invalid_argument("VerifyCalibration: no positions");
  if (!(cal.gravity > 0) || !std::isfinite(cal.gravity) || !(cal.misfit_sigma_raw >= 0)) {
    throw std::invalid_argument(
        "VerifyCalibration: gravity must be positive and the misfit not negative");
  }
  const std::vector<ParameterSlot>& slots = ParameterSlots(cal.model, cal.frame);
  const auto P = static_cast<Eigen::Index>(slots.size());
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
  for (std::size_t k = 0; k < N; ++k) {
    const Position& position = positions[k];
    if (!position.interval)
      throw std::invalid_argument("VerifyCalibration: a position without its interval");
    VerifiedPosition v;
    v.mean_raw = position.mean;
    v.samples = position.samples;
    v.t_begin_s = position.interval->t_begin_s;
    v.t_end_s = position.interval->t_end_s;
    const std::optional<Vec3> f = SpecificForce(cal.params, position.mean);
    if (!f || !(f->norm() > 0)) {
      v.error = v.sigma = v.z = std::numeric_limits<double>::quiet_NaN();
      outside.push_back(k);
      out.positions.push_back(v);
      continue;
    }
    const double norm = f->norm();
    ratios.push_back(norm / cal.gravity);
    Mat33 J = cal.params.K;
    for (int i = 0; i < 3; ++i) J(i, i) += 2 * cal.params.k2(i) * (*f)(i);
    // g = uᵀ J⁻¹: how |f| moves with the reading.
    const Eigen::RowVector3d g = (f->transpose() / norm) * J.inverse();
    const auto row = static_cast<Eigen::Index>(used.size());
    A.row(row) = -g * ModelJacobian(slots, *f);
    const Vec3 mean_variance = MeanVariance(log, position);
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
  // The reason, when it fails: the statistic, then the positions furthest off (1-based, as the
  // files and the tool count them).
  std::vector<std::size_t> worst = out.off_positions;
  std::sort(worst.begin(), worst.end(), [&](std::size_t a, std::size_t b) {
    return std::abs(out.positions[a].z) > std::abs(out.positions[b].z);
  });
  if (worst.size() > 5) worst.resize(5);
  std::string named;
  for (const std::size_t k : worst) {
    named += (named.empty() ? "" : ", ") +
             internal::Format("position %zu (z = %+.1f)", k + 1, out.positions[k].z);
  }
  if (!outside.empty()) {
    out.reason = internal::Format(
        "%zu of %zu positions read outside the range the model can invert (the first: position "
        "%zu)",
        outside.size(), N, outside.front() + 1);
  } else if (out.p_value < options.significance) {
    out.reason = internal::Format(
        "the errors |f| - g are larger than the calibration predicts: chi2 = %.4g for %d "
        "positions (p = %.2g < %.2g)",
        out.chi2, out.dof, out.p_value, options.significance);
    if (!named.empty()) out.reason += "; furthest off: " + named;
  }
  if (!out.reason.empty() && !ratios.empty()) {
    const double ratio = internal::Median(ratios);
    if (std::abs(ratio - 1) > 0.1) {
      out.reason += internal::Format(
          "; |f| is %.3g times g on the median position: is the log in the calibration's raw "
          "unit, and from this sensor?",
          ratio);
    }
  }
  out.passed = out.reason.empty();
  return out;
}

}  // namespace accelcal
