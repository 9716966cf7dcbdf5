#pragma once
/// @file known_orientation.hpp
/// Calibration with known orientations: the general turntable case of paper 003 (Wu et al. 2018,
/// eq. (6)-(8)). The direction of gravity c_k of every position is known in the platform frame
/// (a turntable, dividing head or gimbal readout; orientation_file.hpp), so the model of
/// model.hpp,
///
///     p_k = K g c_k + b + k2 ∘ (g c_k)²,
///
/// is linear in the parameters, with K a full 3x3 matrix: scale factors times eq. (5)'s six small
/// misalignment angles (frame.hpp, Frame::kPlatform; MisalignmentOf names them β). Each output
/// axis i is its own least-squares problem in (K_i·, b_i, k2_i) with regressors
/// (g c_k, 1, (g c_ki)²): weighted by 1/s_ki² when the intervals' sample noise is given, else
/// unweighted with σ̂² = J / (3m − P) (3m equations, P = 12 or 15 parameters). Six axis-aligned
/// positions (±x, ±y, ±z) determine every parameter of either model; orientation-free methods
/// cannot use them (calibrate.hpp).
///
/// The orientations are taken as exact: an orientation error δ of the fixture enters the
/// readings like a misalignment of K (g|K|δ in raw units) and is not in the covariance.

#include <vector>

#include "accelcal/calibrate.hpp"

namespace accelcal {

struct KnownOrientationOptions {
  ModelKind model = ModelKind::kLinear;
  /// Gravity magnitude in the specific-force unit of the result.
  double gravity = kStandardGravity_ms2;
  /// As CalibrationOptions::reading_sigmas: per position, the 1σ of each axis of the averaged
  /// reading [raw]; empty: the noise from the residuals.
  std::vector<Vec3> reading_sigmas;
  /// Leave-one-position-out validation (CalibrationResult::crossval_rms): m refits, each a
  /// closed-form solve.
  bool cross_validate = false;
  /// A position that disagrees with the others (moved or bumped, or the fixture set to another
  /// orientation than the file says), as calibrate.hpp's OutlierPolicy but with the statistic
  /// OutlierStatistic::kFisherF: the position's three residuals against the scatter of the fit
  /// without it, F(3, ν − 3), Bonferroni over the positions, Rosner's generalised ESD. Needs
  /// ν ≥ 4 (linear: 6 positions, quadratic: 7); excluded positions are in no fit and no figure.
  OutlierOptions outliers;

  /// An error message when an option is out of range, else std::nullopt.
  std::optional<std::string> Validate() const;
};

/// Calibrates from averaged readings and their known directions (unit vectors, platform frame,
/// the direction in which each position's specific force points: +z when z is up). The result is
/// in Frame::kPlatform, method SolverMethod::kKnownOrientation (closed form), with the covariance
/// of CalibrationResult (degrees_of_freedom = 3m − P). Throws DataError when the positions do not
/// determine the model (naming the parameter) and std::invalid_argument for invalid options or
/// directions (not unit, not as many as the readings).
CalibrationResult CalibrateKnownOrientations(const std::vector<Vec3>& readings,
                                             const std::vector<Vec3>& directions,
                                             const KnownOrientationOptions& options);

}  // namespace accelcal
