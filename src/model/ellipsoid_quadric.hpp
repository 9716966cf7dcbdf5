#pragma once
// The ellipsoid fit's quadric and what it means (ellipsoid_fit.cpp), shared with its held-out fits
// (held_out.cpp).

#include <optional>
#include <string>

#include <Eigen/Core>

#include "accelcal/model.hpp"

namespace accelcal::internal {

/// The quadric's ten coefficients (a, b, c, 2f, 2g, 2h, 2p, 2q, 2r, d) of
/// x'Qx + 2L'x + c = 0 in scaled coordinates.
using Vec10 = Eigen::Matrix<double, 10, 1>;

/// K and b from a quadric in the scaled coordinates q = (p − mean) / scale, or the reason why the
/// quadric is not a real ellipsoid.
std::optional<std::string> QuadricToParameters(const Vec10& v, const Vec3& mean, double scale,
                                               double gravity, ModelParameters* params);

}  // namespace accelcal::internal
