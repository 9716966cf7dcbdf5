#include "accelcal/gimbal_platform.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "accelcal/error.hpp"
#include "accelcal/known_orientation.hpp"
#include "core/text_format.hpp"
#include "platform/gimbal_internal.hpp"
#include "solvers/least_squares.hpp"

namespace accelcal {

namespace {

constexpr int kParameters = 14;  // s(3), δb(3), β(6), θ20, θ30
using Vec14 = Eigen::Matrix<double, kParameters, 1>;
using Mat14 = Eigen::Matrix<double, kParameters, kParameters>;

PlatformAccelerometer Unpack14(const Vec14& p) {
  PlatformAccelerometer d;
  d.s = p.segment<3>(0);
  d.bias = p.segment<3>(3);
  d.beta = p.segment<6>(6);
  return d;
}

// The options shared by the two stages' checks.
std::optional<std::string> ValidateStage(double gravity, int max_iterations, double step_tolerance,
                                         double initial_damping, double min_rcond) {
  if (!(gravity > 0) || !std::isfinite(gravity)) return "gravity must be a positive number";
  if (max_iterations < 1) return "max_iterations must be at least 1";
  if (!(step_tolerance >= 0) || !std::isfinite(step_tolerance)) {
    return "step_tolerance must be a non-negative number";
  }
  if (!(initial_damping >= 0) || !std::isfinite(initial_damping)) {
    return "initial_damping must be a non-negative number";
  }
  if (!(min_rcond > 0 && min_rcond < 1)) return "min_reciprocal_condition must lie in (0, 1)";
  return std::nullopt;
}

template <typename Options>
void ThrowIfInvalid(const Options& options) {
  if (const auto error = options.Validate()) throw std::invalid_argument(*error);
}

PlatformSummary ToPlatformSummary(const internal::LeastSquaresSummary& s) {
  PlatformSummary out;
  out.iterations = s.iterations;
  out.termination = s.termination;
  out.termination_message = s.termination_message;
  out.initial_cost = s.initial_cost;
  out.final_cost = s.final_cost;
  return out;
}

// Eq. (7) as a least-squares problem: one residual block, predicted − measured outputs (3m),
// in the 14 parameters.
class CoarseProblem : public internal::LeastSquaresProblem {
 public:
  CoarseProblem(const std::vector<Vec3>& outputs, const std::vector<Vec3>& commanded,
                double gravity)
      : outputs_(outputs), commanded_(commanded), gravity_(gravity) {}
  int GlobalSize() const override { return kParameters; }
  int NumBlocks() const override { return 1; }
  bool Evaluate(int /*block*/, const Eigen::VectorXd& x, const Eigen::VectorXd& /*y*/,
                Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                Eigen::MatrixXd* /*J_y*/) const override {
    internal::CoarseJacobian J;
    *residual = internal::CoarsePrediction(commanded_, gravity_, x, J_x != nullptr ? &J : nullptr);
    for (std::size_t k = 0; k < outputs_.size(); ++k) {
      residual->segment<3>(static_cast<Eigen::Index>(3 * k)) -= outputs_[k];
    }
    if (J_x != nullptr) *J_x = J;
    return true;
  }

 private:
  const std::vector<Vec3>& outputs_;
  const std::vector<Vec3>& commanded_;
  double gravity_;
};

// The fine stage's state: the device (s, δb, β, K_nl: 15 values) followed by the sum of the
// steps dx taken (12); the tangent is dx, applied by the full-value update of eq. (17).
using FineState = Eigen::Matrix<double, 27, 1>;
PlatformAccelerometer UnpackFine(const Eigen::VectorXd& x) {
  PlatformAccelerometer d;
  d.s = x.segment<3>(0);
  d.bias = x.segment<3>(3);
  d.beta = x.segment<6>(6);
  d.k_nl = x.segment<3>(12);
  return d;
}
Eigen::VectorXd PackFine(const PlatformAccelerometer& d, const Eigen::Matrix<double, 12, 1>& sum) {
  FineState x;
  x << d.s, d.bias, d.beta, d.k_nl, sum;
  return x;
}

// Σ_j z_j², z_j = ½(g² − |f̂^p_j|²) of the device, with the Jacobian −A of eq. (16) (the rows
// neglect the device's own small errors: an approximate Gauss-Newton).
class FineProblem : public internal::LeastSquaresProblem {
 public:
  FineProblem(const std::vector<Vec3>& outputs, double gravity)
      : outputs_(outputs), gravity_(gravity) {}
  int GlobalSize() const override { return 12; }
  int NumBlocks() const override { return 1; }
  bool Evaluate(int /*block*/, const Eigen::VectorXd& x, const Eigen::VectorXd& /*y*/,
                Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                Eigen::MatrixXd* /*J_y*/) const override {
    Eigen::Matrix<double, Eigen::Dynamic, 12> A;
    *residual =
        internal::FineObservation(outputs_, UnpackFine(x), gravity_, J_x != nullptr ? &A : nullptr);
    if (J_x != nullptr) *J_x = -A;
    return true;
  }
  Eigen::VectorXd PlusGlobal(const Eigen::VectorXd& x,
                             const Eigen::VectorXd& delta) const override {
    PlatformAccelerometer d = UnpackFine(x);
    const Eigen::Matrix<double, 12, 1> dx = delta;
    internal::ApplyFineUpdate(dx, &d);
    return PackFine(d, x.tail<12>() + dx);
  }

 private:
  const std::vector<Vec3>& outputs_;
  double gravity_;
};

}  // namespace

std::string PlatformSummary::BriefReport() const {
  return std::string(ToString(termination)) + " (" + termination_message + ") after " +
         std::to_string(iterations) + " iterations";
}

std::optional<std::string> CoarseCalibrationOptions::Validate() const {
  return ValidateStage(gravity, max_iterations, step_tolerance, initial_damping,
                       min_reciprocal_condition);
}

std::optional<std::string> FineCalibrationOptions::Validate() const {
  return ValidateStage(gravity, max_iterations, step_tolerance, initial_damping,
                       min_reciprocal_condition);
}

std::optional<std::string> IteratedCoarseCalibrationOptions::Validate() const {
  if (auto error = coarse.Validate()) return error;
  if (!(offset_tolerance_rad > 0) || !std::isfinite(offset_tolerance_rad)) {
    return "offset_tolerance_rad must be a positive number";
  }
  if (max_rounds < 1) return "max_rounds must be at least 1";
  return std::nullopt;
}

namespace internal {

Eigen::VectorXd CoarsePrediction(const std::vector<Vec3>& commanded, double gravity,
                                 const CoarseParameters& q, CoarseJacobian* J) {
  const std::size_t m = commanded.size();
  const PlatformAccelerometer d = Unpack14(q);
  const Mat33 C = InstallationMatrix(d.beta);
  Eigen::VectorXd predicted(3 * m);
  if (J != nullptr) J->resize(static_cast<Eigen::Index>(3 * m), kParameters);
  for (std::size_t k = 0; k < m; ++k) {
    Mat33 du;
    const Vec3 angles = commanded[k] + Vec3(0.0, q(12), q(13));
    const Vec3 f = gravity * PlatformUp(angles, &du);
    const Vec3 Cf = C * f;
    const auto row = static_cast<Eigen::Index>(3 * k);
    predicted.segment<3>(row) = d.s.cwiseProduct(Cf) + d.bias;
    if (J == nullptr) continue;
    auto Jk = J->middleRows<3>(row);
    Jk.setZero();
    for (int i = 0; i < 3; ++i) {
      Jk(i, i) = Cf(i);    // ∂/∂s_i
      Jk(i, 3 + i) = 1.0;  // ∂/∂δb_i
    }
    Jk(0, 6) = d.s(0) * f(1);    // β_xz
    Jk(0, 7) = -d.s(0) * f(2);   // β_xy
    Jk(1, 8) = -d.s(1) * f(0);   // β_yz
    Jk(1, 9) = d.s(1) * f(2);    // β_yx
    Jk(2, 10) = d.s(2) * f(0);   // β_zy
    Jk(2, 11) = -d.s(2) * f(1);  // β_zx
    const Mat33 dC = d.s.asDiagonal() * C * gravity * du;
    Jk.col(12) = dC.col(1);  // θ20
    Jk.col(13) = dC.col(2);  // θ30
  }
  return predicted;
}

Eigen::VectorXd FineObservation(const std::vector<Vec3>& outputs, const PlatformAccelerometer& d,
                                double gravity, Eigen::Matrix<double, Eigen::Dynamic, 12>* A) {
  const std::size_t m = outputs.size();
  const Mat33 C_inverse = InstallationMatrix(d.beta).inverse();  // Ĉ_a^p
  Eigen::VectorXd z(m);
  if (A != nullptr) A->resize(static_cast<Eigen::Index>(m), 12);
  for (std::size_t j = 0; j < m; ++j) {
    // v = ŜF (f^a − δ̂b) with the nonlinear term of eq. (8) removed as far as it is known.
    const Vec3 deviation = outputs[j] - d.bias;
    const Vec3 v = (deviation - d.k_nl.cwiseProduct(deviation.cwiseAbs2())).cwiseQuotient(d.s);
    const Vec3 f_p = C_inverse * v;
    const auto row = static_cast<Eigen::Index>(j);
    z(row) = 0.5 * (gravity * gravity - f_p.squaredNorm());
    if (A == nullptr) continue;
    A->row(row) << v(0) * v(0), v(1) * v(1), v(2) * v(2), -v(0), -v(1), -v(2), -v(0) * v(0) * v(0),
        -v(1) * v(1) * v(1), -v(2) * v(2) * v(2), v(0) * v(1), v(0) * v(2), v(1) * v(2);
  }
  return z;
}

void ApplyFineUpdate(const Eigen::Matrix<double, 12, 1>& dx, PlatformAccelerometer* device) {
  PlatformAccelerometer& d = *device;
  // Full-value update (the paper's "using scale factors to convert the solved dx").
  for (int i = 0; i < 3; ++i) {
    const double sf = 1.0 / d.s(i);  // ŜF_i
    d.bias(i) += dx(3 + i) / sf;
    d.k_nl(i) += dx(6 + i) * sf;
    d.s(i) /= 1.0 + dx(i);
  }
  d.beta(2) += dx(9) / 2;   // β_yz
  d.beta(0) -= dx(9) / 2;   // β_xz
  d.beta(1) += dx(10) / 2;  // β_xy
  d.beta(4) -= dx(10) / 2;  // β_zy
  d.beta(5) += dx(11) / 2;  // β_zx
  d.beta(3) -= dx(11) / 2;  // β_yx
}

}  // namespace internal

CoarseCalibrationResult CoarseCalibration(const std::vector<Vec3>& outputs,
                                          const std::vector<Vec3>& commanded,
                                          const CoarseCalibrationOptions& options) {
  ThrowIfInvalid(options);
  const double gravity = options.gravity;
  const std::size_t m = outputs.size();
  if (commanded.size() != m) {
    throw DataError(std::to_string(commanded.size()) + " commanded positions for " +
                    std::to_string(m) + " outputs");
  }
  if (3 * m < kParameters + 1) {
    throw DataError("the coarse stage needs at least 5 positions, got " + std::to_string(m));
  }
  // Start: the known-orientation least squares at the commanded angles (offsets zero), K = diag(s)
  // C_p^a read to first order.
  std::vector<Vec3> directions;
  for (const Vec3& a : commanded) directions.push_back(PlatformUp(a));
  KnownOrientationOptions start_options;
  start_options.gravity = gravity;
  const ModelParameters start =
      CalibrateKnownOrientations(outputs, directions, start_options).params;
  Vec14 p = Vec14::Zero();
  for (int i = 0; i < 3; ++i) p(i) = start.K(i, i);
  p.segment<3>(3) = start.bias;
  p(6) = start.K(0, 1) / start.K(0, 0);
  p(7) = -start.K(0, 2) / start.K(0, 0);
  p(8) = -start.K(1, 0) / start.K(1, 1);
  p(9) = start.K(1, 2) / start.K(1, 1);
  p(10) = start.K(2, 0) / start.K(2, 2);
  p(11) = -start.K(2, 1) / start.K(2, 2);

  internal::LeastSquaresOptions solver;
  solver.max_iterations = options.max_iterations;
  // Converged when no step moves a prediction by more than step_tolerance of the signal.
  solver.step_tolerance = options.step_tolerance * gravity * p.head<3>().maxCoeff();
  solver.initial_damping = options.initial_damping;
  solver.min_reciprocal_condition = options.min_reciprocal_condition;
  internal::LeastSquaresState state{p, {}};
  const internal::LeastSquaresSummary s =
      internal::SolveLeastSquares(CoarseProblem(outputs, commanded, gravity), solver, &state);
  if (s.rank_deficient) {
    throw DataError(
        "the positions do not determine the coarse-stage parameters (reciprocal "
        "condition " +
        internal::Format("%.3g", s.reciprocal_condition) + "): use Table 1's 18 positions");
  }
  p = state.x;
  CoarseCalibrationResult result;
  result.summary = ToPlatformSummary(s);
  if (s.termination == TerminationType::kParameterTolerance) {
    result.summary.termination_message =
        internal::Format("max_k |(J dp)_k| = %.3e <= %.1e g max_i s_i = %.3e", s.step_change,
                         options.step_tolerance, solver.step_tolerance);
  }
  result.device = Unpack14(p);
  result.offsets = Vec3(0.0, p(12), p(13));
  result.residual_rms = std::sqrt(s.final_cost / static_cast<double>(3 * m));
  result.covariance = s.covariance;
  result.std = result.covariance.diagonal().cwiseSqrt();
  result.note =
      "theta10 (the platform's own axis) is not separable from the installation angles: held at "
      "0, its effect is in beta_xz and beta_yz";
  return result;
}

CoarseCalibrationResult IteratedCoarseCalibration(
    const std::function<std::vector<Vec3>(const std::vector<Vec3>& commanded)>& measure,
    const IteratedCoarseCalibrationOptions& options) {
  ThrowIfInvalid(options);
  Vec3 correction = Vec3::Zero();
  CoarseCalibrationResult result;
  const std::vector<Vec3> nominal = Wu2018Table1Angles();
  PlatformSummary loop;
  loop.termination = TerminationType::kMaxIterations;
  loop.termination_message = internal::Format("reached max_rounds = %d", options.max_rounds);
  for (int round = 0; round < options.max_rounds; ++round) {
    // Re-zeroing the angle sensors by the offsets found so far: the gimbals turn to the nominal
    // angles minus the correction in the original readings, and the fit, given the nominal
    // angles, sees only the offset that is left.
    std::vector<Vec3> commanded = nominal;
    for (Vec3& a : commanded) a -= correction;
    result = CoarseCalibration(measure(commanded), nominal, options.coarse);
    correction += result.offsets;
    ++loop.iterations;
    if (round == 0) loop.initial_cost = result.summary.initial_cost;
    loop.final_cost = result.summary.final_cost;
    if (!result.summary.converged()) {
      // A run that did not converge ends the loop with its reason.
      loop.termination = result.summary.termination;
      loop.termination_message =
          internal::Format("round %d: ", round + 1) + result.summary.termination_message;
      break;
    }
    const double latest = result.offsets.cwiseAbs().maxCoeff();
    if (latest < options.offset_tolerance_rad) {
      loop.termination = TerminationType::kParameterTolerance;
      loop.termination_message =
          internal::Format("max(|theta20|, |theta30|) of round %d = %.3e < %.1e rad", round + 1,
                           latest, options.offset_tolerance_rad);
      break;
    }
  }
  result.offsets = correction;
  result.rounds = loop.iterations;
  result.summary = loop;
  return result;
}

FineCalibrationResult FineCalibration(const std::vector<Vec3>& outputs,
                                      const PlatformAccelerometer& coarse,
                                      const FineCalibrationOptions& options) {
  ThrowIfInvalid(options);
  const double gravity = options.gravity;
  const std::size_t m = outputs.size();
  if (m < 13) {
    throw DataError("the fine stage needs at least 13 positions (12 unknowns), got " +
                    std::to_string(m));
  }
  internal::LeastSquaresOptions solver;
  solver.max_iterations = options.max_iterations;
  solver.step_tolerance = options.step_tolerance * gravity * gravity;
  solver.initial_damping = options.initial_damping;
  solver.min_reciprocal_condition = options.min_reciprocal_condition;
  internal::LeastSquaresState state{PackFine(coarse, Eigen::Matrix<double, 12, 1>::Zero()), {}};
  const internal::LeastSquaresSummary s =
      internal::SolveLeastSquares(FineProblem(outputs, gravity), solver, &state);
  if (s.rank_deficient) {
    throw DataError("the positions do not determine the fine-stage error vector (eq. (17))");
  }
  FineCalibrationResult result;
  result.summary = ToPlatformSummary(s);
  if (s.termination == TerminationType::kParameterTolerance) {
    result.summary.termination_message =
        internal::Format("max_j |(A dx)_j| = %.3e <= %.1e g^2 = %.3e", s.step_change,
                         options.step_tolerance, solver.step_tolerance);
  }
  result.device = UnpackFine(state.x);
  result.dx = state.x.tail<12>();
  result.dx_std = s.covariance.diagonal().cwiseSqrt();
  result.residual_rms = std::sqrt(s.final_cost / static_cast<double>(m)) / gravity;
  result.note =
      "the pairs (beta_xz, beta_yz), (beta_zy, beta_xy), (beta_yx, beta_zx) are not separable here "
      "(paper 003 section 4): gravity magnitudes determine only beta_yz - beta_xz, beta_xy - "
      "beta_zy, beta_zx - beta_yx; each pair was moved symmetrically, its sum kept from the coarse "
      "stage";
  return result;
}

}  // namespace accelcal
