#pragma once
/// @file ellipsoid_fit.hpp
/// Algebraic ellipsoid fit of raw readings (paper 001 §3.3, eq. (16)-(18)).
///
/// Readings of a linear accelerometer satisfy (p − b)ᵀ K⁻ᵀ K⁻¹ (p − b) = g². The general quadric
/// pᵀ Q p + 2 Lᵀ p + c = 0 is fitted by total least squares (the right singular vector of the
/// smallest singular value of the column-normalised design matrix); then b = −Q⁻¹ L and, with
/// s = bᵀ Q b − c, K Kᵀ = (s / g²) Q⁻¹, so K is the lower Cholesky factor: the gauge of model.hpp.

#include <optional>
#include <string>
#include <vector>

#include "accelcal/model.hpp"

namespace accelcal {

struct EllipsoidFitResult {
  ModelParameters params;  ///< K (lower-triangular, positive diagonal) and b; k2 = 0
  bool ok = false;         ///< false: the quadric is not an ellipsoid (or too few readings)
  std::string failure;     ///< why, when !ok
};

/// Needs at least 9 readings; gravity is the magnitude in the specific-force unit.
EllipsoidFitResult FitEllipsoid(const std::vector<Vec3>& readings, double gravity);

}  // namespace accelcal
