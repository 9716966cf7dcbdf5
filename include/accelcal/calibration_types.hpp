#pragma once
/// @file calibration_types.hpp
/// The vocabulary of a calibration shared by every layer above the model: the options of
/// Calibrate (calibrate.hpp) and its sibling estimators, the solver's Summary and the
/// CalibrationResult, with their name tables; and the |f| − g check of a fit.

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "accelcal/bias_drift.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/model.hpp"
#include "accelcal/names.hpp"
#include "accelcal/thermal.hpp"

namespace accelcal {

enum class SolverMethod {
  kTwoStep,         ///< "two-step": paper 000 alternating least squares / per-position KKT Newton
  kJoint,           ///< "joint": Levenberg-Marquardt with Schur complement
  kModulus,         ///< "modulus": min Σ (|f_k|²/g² − 1)², paper 001's least-squares baseline
  kModulusNorm,     ///< "modulus-norm": min Σ (|f_k|/g − 1)², the variant on the norm
  kNewtonLagrange,  ///< "newton-lagrange": paper 001 §3.2, Newton on the Lagrangian, linear model
  kEllipsoid,  ///< "ellipsoid": paper 001 §3.3, the algebraic ellipsoid fit itself, linear model
  /// "known-orientation": linear least squares with the direction of every position known
  /// (known_orientation.hpp); Calibrate() refuses it, CalibrateKnownOrientations() uses it.
  kKnownOrientation,
};
/// Whether a method estimates by maximum likelihood (and so carries a covariance). The modulus
/// methods do not: their residual (|f|² − g²) has a noise-dependent mean (paper 001 eq. (11)).
constexpr bool IsMaximumLikelihood(SolverMethod method) {
  return method == SolverMethod::kTwoStep || method == SolverMethod::kJoint ||
         method == SolverMethod::kNewtonLagrange || method == SolverMethod::kKnownOrientation;
}
std::string_view ToString(SolverMethod method);
std::optional<SolverMethod> SolverMethodFromString(std::string_view text);
template <>
struct EnumNames<SolverMethod> {
  static constexpr std::pair<SolverMethod, std::string_view> kTable[] = {
      {SolverMethod::kJoint, "joint"},
      {SolverMethod::kTwoStep, "two-step"},
      {SolverMethod::kNewtonLagrange, "newton-lagrange"},
      {SolverMethod::kModulus, "modulus"},
      {SolverMethod::kModulusNorm, "modulus-norm"},
      {SolverMethod::kEllipsoid, "ellipsoid"},
      {SolverMethod::kKnownOrientation, "known-orientation"}};
};

/// Which estimate the maximum-likelihood methods return.
///
/// With every direction a free parameter, the ML estimate is biased at MEMS noise levels (the
/// incidental-parameter problem): a noisy reading lies on average outside the fitted surface, by
/// the expected signed distance m_k = −½ tr(L_k G_k⁻¹ T_kᵀ Σ_k T_k G_k⁻¹) (T_k the surface's
/// tangent vectors ∂μ/∂s at the foot point, G_k = T_kᵀT_k, L_k = n_k·∂²μ/∂s∂s its second
/// fundamental form, Σ_k the reading's noise covariance). For a sphere of radius g|K| this is
/// σ²/(g|K|): the scale factors come out too large by σ²/(g²K) relative
/// (docs/errata.md#001-ml-bias, paper 001).
enum class Estimator {
  kMaximumLikelihood,  ///< "ml": the optimum of J (paper 000 eq. (13), paper 001 eq. (12))
  /// "bias-corrected": the ML equations solved with each reading moved m_k inward along the
  /// surface normal n_k, p̃_k = p_k − m_k n_k, refitted until the shifts settle (a corrected
  /// score: its expectation at the truth vanishes to second order in the noise). m_k uses the
  /// noise of the covariance (reading_sigmas times max(1, R²), or σ̂ from the residuals). The
  /// covariance is the ML one (equal to first order); residuals stay p_k − μ.
  kBiasCorrected,
};
std::string_view ToString(Estimator estimator);
std::optional<Estimator> EstimatorFromString(std::string_view text);
template <>
struct EnumNames<Estimator> {
  static constexpr std::pair<Estimator, std::string_view> kTable[] = {
      {Estimator::kMaximumLikelihood, "ml"}, {Estimator::kBiasCorrected, "bias-corrected"}};
};

enum class Initialization {
  kAuto,                ///< ellipsoid fit, falling back to normalised readings if it fails
  kEllipsoidFit,        ///< ellipsoid fit only (DataError when neither fit gives an ellipsoid)
  kNormalizedReadings,  ///< paper 000 eq. (26): c_k = p_k / |p_k|
  kGiven,               ///< CalibrationOptions::initial_params (e.g. a nominal device, a previous
                        ///< calibration, or the full fit when a position is held out)
};
std::string_view ToString(Initialization init);
std::optional<Initialization> InitializationFromString(std::string_view text);
template <>
struct EnumNames<Initialization> {
  static constexpr std::pair<Initialization, std::string_view> kTable[] = {
      {Initialization::kAuto, "auto"},
      {Initialization::kEllipsoidFit, "ellipsoid"},
      {Initialization::kNormalizedReadings, "normalized-readings"},
      {Initialization::kGiven, "given"}};
};

/// Why a solver stopped. The criteria, with Δ measured in the parameter metric ‖·‖_s (each
/// parameter change converted to the change of the prediction it causes, in raw units, divided by
/// the signal amplitude |K_ii|·g of its axis; max-norm):
enum class TerminationType {
  kParameterTolerance,  ///< two-step: ‖Δθ_n‖_s·ρ/(1−ρ) ≤ parameter_tolerance, ρ =
                        ///< ‖Δθ_n‖_s/‖Δθ_{n−1}‖_s (the remaining error of a linearly converging
                        ///< sequence); joint: ‖Δθ‖_s ≤ parameter_tolerance and every |Δc_k| ≤
                        ///< parameter_tolerance; newton-lagrange: δ_n = max(‖Δθ‖_s, max|Δc_k|)
                        ///< ≤ parameter_tolerance, or, once δ_{n−1} < 1e-3, the predicted next
                        ///< step 10 κ δ_n² ≤ parameter_tolerance with κ the largest observed
                        ///< δ_j / δ_{j−1}² (quadratic convergence)
  kFunctionTolerance,  ///< |J_{n−1} − J_n| ≤ function_tolerance · J_n
  kZeroResidual,       ///< J ≤ (8 ε · signal)² · 3m: the data are fitted to round-off
  kMaxIterations,      ///< iteration cap reached before any criterion: not converged
  kClosedForm,         ///< ellipsoid: a direct solution, no iteration
  kNoProgress,         ///< joint, modulus, newton-lagrange: no step reduced the cost even with
                       ///< maximal damping, or Newton diverged: not converged
};
std::string_view ToString(TerminationType type);
template <>
struct EnumNames<TerminationType> {
  static constexpr std::pair<TerminationType, std::string_view> kTable[] = {
      {TerminationType::kParameterTolerance, "parameter_tolerance"},
      {TerminationType::kFunctionTolerance, "function_tolerance"},
      {TerminationType::kZeroResidual, "zero_residual"},
      {TerminationType::kMaxIterations, "max_iterations"},
      {TerminationType::kClosedForm, "closed_form"},
      {TerminationType::kNoProgress, "no_progress"}};
};

/// Screening of the positions for one that does not agree with the others: a position recorded
/// while the sensor crept, or knocked during its interval, averages to a reading off the fitted
/// surface by far more than the scatter of the other positions. At a converged fit of m positions
/// and P parameters, each position's residual along the surface normal, e_k = n_kᵀ r_k [raw], is
/// compared with the scatter of the rest by the externally studentised residual of linear least
/// squares (the fit linearised at the solution, with the directions eliminated):
///
///     r_k = e_k / (s √(1 − h_k)),  s² = Σ e_j² / ν,  ν = m − P,  h_k = u_kᵀ S⁻¹ u_k
///     t_k = r_k √((ν − 1) / (ν − r_k²))   (Student's t with ν − 1 degrees of freedom)
///
/// (u_k and S = Σ u_j u_jᵀ as in CalibrationResult::covariance; t_k is the residual of position k
/// against the fit of the others, scaled by their scatter, computed without refitting). The
/// noise level is the scatter of the positions themselves, never the samples' white noise alone,
/// which real recordings exceed (CalibrationResult::scatter_ratio). The largest |t_k| is
/// discordant when its two-sided probability, times m (Bonferroni), is below
/// `false_alarm_probability`: the chance that a calibration whose positions all agree loses one.
/// Two discordant positions inflate s and can hide each other; so the test is Rosner's (1983)
/// generalised ESD: the most discordant position is removed and the rest refitted, up to
/// max(1, max_excluded) times, each step tested against its own threshold, and the number of
/// discordant positions is the last step that exceeds it. These refits run only when the first
/// step is significant or some position is beyond the threshold on a robust scale (1.4826 times
/// the median |e_k| / √(1 − h_k)). Needs ν ≥ 2; positions with h_k > 1 − 1e-9 (the others cannot
/// predict them) are not tested.
enum class OutlierPolicy {
  kOff,      ///< "off": no screening
  kFlag,     ///< "flag": findings in CalibrationResult::outliers, every position stays in the fit
  kExclude,  ///< "exclude": the discordant positions are left out of the fit (at most
             ///< `max_excluded`; any more are flagged)
};
std::string_view ToString(OutlierPolicy policy);
std::optional<OutlierPolicy> OutlierPolicyFromString(std::string_view text);
template <>
struct EnumNames<OutlierPolicy> {
  static constexpr std::pair<OutlierPolicy, std::string_view> kTable[] = {
      {OutlierPolicy::kExclude, "exclude"},
      {OutlierPolicy::kFlag, "flag"},
      {OutlierPolicy::kOff, "off"}};
};

struct OutlierOptions {
  OutlierPolicy policy = OutlierPolicy::kExclude;
  double false_alarm_probability = 1e-3;  ///< per calibration, see OutlierPolicy
  /// At most this many positions are excluded (and max(1, max_excluded) tested): many positions
  /// that disagree point at the model or the recording, not at single bad positions.
  int max_excluded = 3;

  /// An error message when an option is out of range, else std::nullopt.
  std::optional<std::string> Validate() const;
};

/// The statistic of an outlier test.
enum class OutlierStatistic {
  /// Orientation-free fits (Calibrate): t_k, the externally studentised residual along the
  /// fitted surface's normal, Student t with ν − 1 degrees of freedom.
  kStudentT,
  /// Known orientations (known_orientation.hpp): F_k, the position's three residuals against
  /// the scatter of the fit without it, Fisher F with 3 and ν − 3 degrees of freedom.
  kFisherF,
};
std::string_view ToString(OutlierStatistic statistic);  // "t", "F"

/// A position the screening found discordant (OutlierPolicy).
struct OutlierFinding {
  int position = 0;  ///< 0-based index into the readings
  OutlierStatistic statistic = OutlierStatistic::kStudentT;
  double t = 0;                ///< the statistic when it was found: t_k, or F_k for kFisherF
  double threshold = 0;        ///< the |t_k| (or F_k) that false_alarm_probability allowed then
  int degrees_of_freedom = 0;  ///< of t_k, ν − 1; for kFisherF the second, ν − 3 (the first is 3)
  double normal_residual = 0;  ///< e_k [raw]; for kFisherF the length of the residual p_k − μ_k
  double scatter = 0;          ///< s of that fit [raw]; for kFisherF of the fit without it,
                               ///< per axis (a ratio to the samples' noise when they weight it)
  bool excluded = false;       ///< left out of the result's fit
};

struct CalibrationOptions {
  ModelKind model = ModelKind::kLinear;
  /// kJoint is the default: measured 35x faster than kTwoStep to the same optimum
  /// (BENCHMARKS.md).
  SolverMethod method = SolverMethod::kJoint;
  Initialization initialization = Initialization::kAuto;
  /// Body frame of the result (frame.hpp): x-first (K lower-triangular, paper 000) or z-first (K
  /// upper-triangular, paper 001, imu_tk). The z-first fit is the x-first fit of the mirrored
  /// readings, so both reach their optimum alike; for the quadratic model the two are different
  /// models (k2 ∘ f² squares the body-frame components).
  Frame frame = Frame::kXFirst;
  /// Gravity magnitude in the specific-force unit of the result (9.80665 for m/s², 1 for g).
  double gravity = kStandardGravity_ms2;
  /// Parameters to start from, in `frame`, with initialization kGiven (required then, and used
  /// only then); the directions start as the normalised corrected readings.
  std::optional<ModelParameters> initial_params;
  /// The noise of the readings when the data give it: per position, the 1σ of each axis of the
  /// averaged reading [raw] (the interval's sample standard deviation over √samples). Empty: the
  /// covariance takes the noise from the residuals. Must match the readings in number, finite and
  /// positive. See CalibrationResult::covariance.
  std::vector<Vec3> reading_sigmas;
  /// Leave-one-position-out validation (CalibrationResult::crossval_rms): the fit without each
  /// position from the full fit's expansion (held_out.hpp: O(m) in all, refits only where the
  /// expansion cannot be trusted). Off by default in the library; the command line turns it on.
  bool cross_validate = false;
  /// Screening for discordant positions (see OutlierPolicy): on by default, excluding.
  OutlierOptions outliers;
  /// Maximum-likelihood methods only.
  Estimator estimator = Estimator::kMaximumLikelihood;
  /// The bias as a function of time within the session (bias_drift.hpp): constant by default.
  /// Any other model is fitted jointly with the rest by the joint method (kJoint) and the
  /// maximum-likelihood estimator, and needs position_times_s.
  BiasModel bias_model;
  /// The time of each reading [s], the middle of its still interval: one per reading, required
  /// when bias_model is not constant (and then used only then).
  std::vector<double> position_times_s;
  /// The drift's basis; empty: BiasTimeBasis::For(bias_model, position_times_s). A fit of some
  /// of the positions (screening, held-out) is given the full set's, so that its knots and
  /// reference time are the same.
  std::optional<BiasTimeBasis> bias_basis;
  /// The random walk of the bias, q per axis [raw/√s] (the Allan deviation's K, noise_model.hpp):
  /// with a spline bias, the knot biases' increments are given the prior N(0, q² Δτ), so that
  /// many knots follow a wandering bias without fitting the noise (drift_fit.hpp). Ignored by the
  /// other bias models; finite and positive.
  std::optional<Vec3> bias_random_walk;

  /// Estimator::kBiasCorrected: refit until no reading's shift changes by more than
  /// `tolerance` times its noise along the normal (then the parameters are settled far below
  /// their standard deviation); not settling within `max_rounds` refits ends as kMaxIterations.
  struct BiasCorrection {
    int max_rounds = 10;
    double tolerance = 1e-6;
  } bias_correction;

  struct TwoStep {
    int max_sweeps = 20000;              ///< cap on alternations
    double parameter_tolerance = 1e-14;  ///< see TerminationType
    /// 0 disables the cost criterion, the default: J stops changing in floating point while the
    /// parameters are still moving (docs/errata.md#000-convergence; measured on the paper 001
    /// problem, σ = 0.1 g: J constant to the last bit 1.9e-8 away from the optimum).
    double function_tolerance = 0.0;
    int max_newton_iterations = 50;  ///< per-position KKT Newton cap (eq. (21))
  } two_step;

  struct Joint {
    int max_iterations = 100;
    double parameter_tolerance = 1e-14;
    /// 0 disables the cost criterion, the default: near the optimum of a large-residual problem
    /// a step of 1e-9 changes J by 1e-17 of itself, so a relative cost criterion stops early.
    double function_tolerance = 0.0;
    double initial_damping = 1e-9;  ///< λ, relative to the diagonal of the normal matrix
  } joint;

  /// The modulus methods (Levenberg-Marquardt on the 9 linear parameters; the criteria as for
  /// the joint solver, on the parameters only).
  struct Modulus {
    int max_iterations = 200;
    double parameter_tolerance = 1e-14;
    double function_tolerance = 1e-16;
  } modulus;

  /// Paper 001's Newton iteration (no line search, as in the paper): stops when the step, or the
  /// next step predicted from quadratic convergence, is below the tolerance in the metric of
  /// TerminationType; a diverging start ends as kNoProgress.
  struct NewtonLagrange {
    int max_iterations = 50;
    double parameter_tolerance = 1e-14;
  } newton_lagrange;

  /// An error message when an option is out of range, else std::nullopt.
  std::optional<std::string> Validate() const;
};

/// How the solve went (Ceres-style).
struct Summary {
  SolverMethod method = SolverMethod::kJoint;
  Initialization initialization = Initialization::kAuto;  ///< what was actually used
  std::string initialization_note;  ///< e.g. why the ellipsoid fit was not used
  int iterations = 0;               ///< sweeps (two-step) or accepted LM steps (joint)
  TerminationType termination = TerminationType::kMaxIterations;
  std::string termination_message;  ///< the criterion met, as a formula with its numbers
  /// The method's own objective at the start and at the solution: J [raw²] for the maximum
  /// likelihood methods, Σ e_k² [dimensionless] for the modulus methods.
  double initial_cost = 0;
  double final_cost = 0;
  double time_s = 0;  ///< wall time of the solve (initialisation included)
  Estimator estimator = Estimator::kMaximumLikelihood;
  /// Estimator::kBiasCorrected: refits with shifted readings after the ML fit (iterations counts
  /// those of every fit; final_cost is J of the shifted readings).
  int correction_rounds = 0;

  bool converged() const {
    return termination != TerminationType::kMaxIterations &&
           termination != TerminationType::kNoProgress;
  }
  std::string BriefReport() const;
};

/// The temperature terms of a calibration whose parameters follow temperature
/// (thermal_calibration.hpp), in the x-first frame.
struct ThermalTerms {
  ThermalParameters params;
  /// Of the thermal flat vector (ThermalSlots order), σ̂² S⁻¹; empty without degrees of freedom.
  Eigen::MatrixXd covariance;
  std::vector<double> temperatures_c;  ///< T_k of each reading [°C]
};

/// Result of a calibration.
struct CalibrationResult {
  ModelKind model = ModelKind::kLinear;
  Frame frame = Frame::kXFirst;           ///< K lower-triangular (x-first) or upper (z-first)
  double gravity = kStandardGravity_ms2;  ///< in the specific-force unit
  ModelParameters params;
  std::vector<Vec3> directions;  ///< estimated unit gravity directions c_k (body frame)
  std::vector<Vec3> residuals;   ///< p_k − μ(θ, g c_k) [raw]
  /// Covariance of the flat parameters (model.hpp order; frame.hpp's for z-first) from the Fisher
  /// information of the joint model with directions eliminated (S = Σ u_k u_kᵀ, information.cpp).
  /// Noise from the residuals, σ̂² = J / (3m − P − 2m): C = σ̂² S⁻¹. With reading_sigmas: the
  /// sandwich C = S⁻¹ (Σ σ_k² u_k u_kᵀ) S⁻¹ with σ_k² = Σ_i n_ki² s_ki² the variance of position
  /// k along the fitted surface's normal, multiplied by the squared scatter ratio R² = χ²/(m − P),
  /// χ² = Σ (n_kᵀ r_k)² / σ_k², when R > 1: white noise that does not explain the scatter of the
  /// positions (model error, drift between positions) must not make the result look better.
  /// Maximum likelihood methods only (IsMaximumLikelihood); empty otherwise, and empty when there
  /// are no residual degrees of freedom (m = P: exactly determined).
  Eigen::MatrixXd covariance;
  /// σ̂ [raw]; 0 when there are no degrees of freedom, or the method estimates no covariance (the
  /// baselines modulus, modulus-norm, ellipsoid)
  double residual_sigma = 0;
  /// Where the covariance's noise came from: "residuals", "samples" (reading_sigmas), or
  /// "joint" (the joint fit with the gyroscope, gyro_calibration.hpp: the residual σ̂ of the
  /// accelerometer's own fit, each of the gyroscope's groups scaled by its scatter ratio).
  std::string noise_source = "residuals";
  /// With reading_sigmas: R = sqrt(χ² / (m − P)), 1 when the per-position noise explains the
  /// scatter of the positions; NaN otherwise. The covariance is multiplied by R² when R > 1.
  double scatter_ratio = std::nan("");
  int degrees_of_freedom = 0;  ///< m − P (m − P − 3J with a drifting bias)
  Summary summary;
  /// With a bias model that is not constant (CalibrationOptions::bias_model): the fitted drift.
  /// `params.bias` is then the bias at its reference time, `residuals` are p_k − μ_k − D φ(t_k),
  /// `covariance` is the model's block of the drift's joint covariance (its uncertainty includes
  /// the drift's), and DriftOffsets gives what to take from each reading before the model is
  /// inverted (|f_k| − g).
  std::optional<BiasDrift> drift;
  /// With parameters that follow temperature: `params` is θ(T_ref), `covariance` its block of the
  /// thermal covariance, `residuals` p_k − μ(θ(T_k), g c_k), and GravityNormErrors takes each
  /// reading under θ(T_k).
  std::optional<ThermalTerms> thermal;
  /// With CalibrationOptions::cross_validate: the RMS of |f_k| − g with each position k corrected
  /// by a fit without it (paper 000 verifies on held-out positions), and the per-position errors.
  /// Absent when some fit without a position fails; crossval_note then says which and why.
  std::optional<double> crossval_rms;
  std::vector<double> crossval_errors;
  std::string crossval_note;
  /// Discordant positions, in the order found (CalibrationOptions::outliers). The fit, its
  /// covariance, cost and degrees of freedom are those of the positions not excluded; the
  /// per-position vectors (directions, residuals, crossval_errors) still have one entry per
  /// reading, an excluded one evaluated under the final fit (its crossval error is then already
  /// held out).
  std::vector<OutlierFinding> outliers;
  /// Why the screening did not run or could not test some position ("" when it ran on all).
  std::string outlier_note;
  /// The screening's policy (OutlierOptions::policy); kOff when it did not run (turned off, or
  /// the fit did not converge).
  OutlierPolicy screening = OutlierPolicy::kOff;
  bool excluded(std::size_t position) const {
    for (const OutlierFinding& o : outliers) {
      if (o.excluded && static_cast<std::size_t>(o.position) == position) return true;
    }
    return false;
  }
  int positions_used() const;
  /// D φ(t_k) of each reading [raw] (zeros for a constant bias): the reading less this is the
  /// reading the model of `params` describes.
  std::vector<Vec3> DriftOffsets(std::size_t readings) const;
  /// The entries of a per-position list (one per reading) at the positions in the fit, in order.
  std::vector<double> InFit(const std::vector<double>& per_position) const;
};

/// |f_k| − g for each reading under `params` (NaN where the model cannot be inverted).
std::vector<double> GravityNormErrors(const ModelParameters& params,
                                      const std::vector<Vec3>& readings, double gravity);
/// |f_k| − g for each reading under a result: its parameters, each reading less its drift offset
/// when the result has a drifting bias (CalibrationResult::DriftOffsets; `readings` are then the
/// fit's, one per position time), each under θ(T_k) when its parameters follow temperature.
std::vector<double> GravityNormErrors(const CalibrationResult& result,
                                      const std::vector<Vec3>& readings);
/// RMS of |p_k| − g with the raw readings taken as specific force (no calibration), or
/// std::nullopt when the readings are evidently not in the specific-force unit (median |p_k| more
/// than 20 % away from g, e.g. raw counts).
std::optional<double> GravityNormRmsUncalibrated(const std::vector<Vec3>& readings, double gravity);
/// Root mean square of a list of values (NaN for an empty list).
double Rms(const std::vector<double>& values);

/// Minimum number of positions for a model: the number of parameters (9 or 12), since each
/// position adds 3 equations and 2 unknown direction angles.
constexpr int MinimumPositions(ModelKind kind) { return NumParameters(kind); }

}  // namespace accelcal
