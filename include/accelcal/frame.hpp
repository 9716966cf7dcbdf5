#pragma once
/// @file frame.hpp
/// Body-frame conventions. Gravity-magnitude data fix the map from specific force to raw output
/// only up to a rotation of the body frame; a convention picks one:
///   - kXFirst (paper 000, accelcal's default): body x = sensor x axis, body y in the sensor x-y
///     plane; K is lower-triangular.
///   - kZFirst (paper 001's T_a, imu_tk): body z = sensor z axis, body y in the sensor y-z plane;
///     K is upper-triangular.

#include <optional>
#include <string_view>

#include "accelcal/model.hpp"

namespace accelcal {

enum class Frame { kXFirst, kZFirst };
std::string_view ToString(Frame frame);  ///< "x-first", "z-first"
std::optional<Frame> FrameFromString(std::string_view text);

/// The same linear map from specific force to raw output expressed in the body frame of `frame`:
/// K' = K Q with Q a rotation, K' lower- (x-first) or upper-triangular (z-first) with positive
/// diagonal. Both satisfy K' K'ᵀ = K Kᵀ, so corrected magnitudes are identical; f' = Qᵀ f.
/// Computed as a Cholesky factor of K Kᵀ (for z-first, of the axis-reversed matrix). Requires an
/// invertible K.
struct FrameChange {
  Mat33 K;          ///< K in the requested frame
  Mat33 Q_old_new;  ///< rotation with K_new = K_old Q_old_new, f_new = Q_old_newᵀ f_old
};
FrameChange ChangeFrame(const Mat33& K, Frame frame);

}  // namespace accelcal
