#pragma once
/// @file thermal_calibration.hpp
/// Calibration with parameters that follow temperature (thermal.hpp): each position carries its
/// mean temperature; scale factors, misalignments, biases (and squared terms) are polynomials in
/// T − T_ref, estimated jointly by maximum likelihood with the positions' directions, from several
/// sessions at different temperatures or one session during a temperature ramp. The simulator of
/// such a device is here too, for planning and Monte Carlo.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/calibration_types.hpp"
#include "accelcal/thermal.hpp"

namespace accelcal {

struct ThermalOptions {
  /// The model, gravity, initialisation and the joint method's limits. The thermal fit is the
  /// joint maximum-likelihood fit in the x-first frame with a constant bias over time: another
  /// method, frame, estimator or bias model is refused (Validate). Its outlier screening and
  /// cross-validation options are not used: see cross_validate below.
  CalibrationOptions base;
  ThermalDegrees degrees;
  /// T_k of each reading [°C] (a position's mean temperature).
  std::vector<double> temperatures_c;
  /// T_ref [°C]; default: the mean of the positions' temperatures.
  std::optional<double> t_ref_c;
  /// Leave-one-position-out held-out errors by refits.
  bool cross_validate = true;

  /// Why these options cannot be used, or nothing.
  std::optional<std::string> Validate() const;
};

struct ThermalResult {
  ModelKind model = ModelKind::kLinear;
  double gravity = 0;
  ThermalParameters params;
  /// Of the thermal flat vector (ThermalSlots order): σ̂² S⁻¹; empty without degrees of freedom.
  Eigen::MatrixXd covariance;
  std::vector<Vec3> directions;  ///< fitted c_k
  std::vector<Vec3> residuals;   ///< p_k − μ(θ(T_k), g c_k) [raw]
  int degrees_of_freedom = 0;    ///< positions − parameters
  double residual_sigma = 0;     ///< σ̂ [raw]
  Summary summary;
  /// Held-out |f| − g of each position under a fit without it, and their rms [gravity's unit];
  /// or why there are none.
  std::vector<double> crossval_errors;
  std::optional<double> crossval_rms;
  std::string crossval_note;
};

/// Throws std::invalid_argument for invalid options or a temperature count that is not one per
/// reading, DataError when the positions' temperatures and orientations do not determine the
/// coefficients (too few temperatures for a degree, or orientations not repeated across them).
ThermalResult CalibrateThermal(const std::vector<Vec3>& readings, const ThermalOptions& options);

/// One step of SelectThermalDegrees: a group's degree raised by one, against the degrees chosen so
/// far.
struct ThermalDegreeStep {
  ThermalDegrees simpler, richer;
  double simpler_rms = 0, richer_rms = 0;  ///< held-out rms |f| − g
  /// Paired held-out evidence as model_selection.hpp's (kHeldOutImprovementAlpha).
  double improvement = 0, improvement_se = 0, improvement_threshold = 0;
  /// Wald test of the added coefficients against 0 (χ² at kThermalAlpha).
  double wald = 0, wald_threshold = 0;
  int wald_dof = 0;
  bool accepted = false;
  std::string error;  ///< why the richer fit could not be compared
};

struct ThermalDegreeSelection {
  ThermalDegrees chosen;
  ThermalResult result;  ///< the chosen degrees' fit, with held-out errors
  std::vector<ThermalDegreeStep> steps;
  std::string reason;
};

/// Significance of a group's added temperature coefficients.
inline constexpr double kThermalAlpha = 0.05;

/// The degrees chosen by held-out error (issue 21): from all zero, each round raises by one the
/// degree of each group in turn (K, b, and k2 for the quadratic model), up to `max_degree`, and
/// keeps the candidate with the largest paired held-out improvement among those that improve
/// beyond sampling error and whose added coefficients are significant; it stops when none does.
/// options.degrees is ignored; cross-validation is always on.
ThermalDegreeSelection SelectThermalDegrees(const std::vector<Vec3>& readings,
                                            ThermalOptions options, int max_degree = 2);

/// |f| − g of each reading under θ(T_k) (NaN where a reading is outside the model's range).
std::vector<double> ThermalGravityNormErrors(const ThermalParameters& params,
                                             const std::vector<Vec3>& readings,
                                             const std::vector<double>& temperatures_c,
                                             double gravity);

/// The thermal fit as a calibration (CalibrationResult::thermal): its parameters θ(T_ref) with
/// their block of the covariance, the directions, residuals, held-out errors and summary, and
/// the temperature terms with `temperatures_c` (one per reading).
CalibrationResult AsCalibrationResult(const ThermalResult& thermal,
                                      const std::vector<double>& temperatures_c);

/// Averaged readings p_k = μ(θ(T_k), g c_k) + v_k, v_k ~ N(0, diag(sigma_raw²)), deterministic in
/// seed (the noise of SimulatePositions with the same seed).
std::vector<Vec3> SimulateThermalPositions(const ThermalParameters& truth, double gravity,
                                           const std::vector<Vec3>& directions,
                                           const std::vector<double>& temperatures_c,
                                           const Vec3& sigma_raw, std::uint64_t seed);

}  // namespace accelcal
