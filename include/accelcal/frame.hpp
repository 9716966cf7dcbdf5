#pragma once
/// @file frame.hpp
/// Body-frame conventions. Gravity-magnitude data fix the map from specific force to raw output
/// only up to a rotation of the body frame; a convention picks one:
///   - kXFirst (paper 000, accelcal's default): body x = sensor x axis, body y in the sensor x-y
///     plane; K is lower-triangular.
///   - kZFirst (paper 001's T_a, imu_tk): body z = sensor z axis, body y in the sensor y-z plane;
///     K is upper-triangular.
///
/// The z-first model is the x-first model of the axis-mirrored problem: with the rotation
/// P = antidiag(1, −1, 1) (P = Pᵀ = P⁻¹, det P = 1), readings P p obey the x-first model with
/// parameters (P K P, P b, P k2) and specific force P f. MirrorAxes maps either way. For the linear
/// model the two frames describe the same device (same corrected magnitudes, ChangeFrame); for the
/// quadratic model they differ, because k2 ∘ f² squares the body-frame components: fit in the
/// frame you want (CalibrationOptions::frame).
///
/// Flat parameter order in the z-first frame (the mirror image of model.hpp's order):
///     quadratic (12): K_zz b_z k2_z | K_yz K_yy b_y k2_y | K_xz K_xy K_xx b_x k2_x
///     linear     (9): K_zz b_z      | K_yz K_yy b_y      | K_xz K_xy K_xx b_x
///
/// A third frame needs more than gravity magnitudes: kPlatform, the frame in which the direction
/// of gravity of every position is known (a turntable's, a dividing head's; paper 003's p-frame).
/// Nothing is left to a convention, so K is a full matrix, scale factors times paper 003 eq. (5)'s
/// six small misalignment angles (known_orientation.hpp). Flat order, by output axis:
///     quadratic (15): K_xx K_xy K_xz b_x k2_x | K_yx K_yy K_yz b_y k2_y | K_zx K_zy K_zz b_z k2_z
///     linear    (12): the same without k2

#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "accelcal/model.hpp"

namespace accelcal {

enum class Frame { kXFirst, kZFirst, kPlatform };
std::string_view ToString(Frame frame);  ///< "x-first", "z-first", "platform"
std::optional<Frame> FrameFromString(std::string_view text);
template <>
struct EnumNames<Frame> {
  static constexpr std::pair<Frame, std::string_view> kTable[] = {
      {Frame::kXFirst, "x-first"}, {Frame::kZFirst, "z-first"}, {Frame::kPlatform, "platform"}};
};

/// The frame K is written in: lower-triangular x-first (a diagonal K too), upper-triangular
/// z-first, else platform.
Frame FrameOf(const Mat33& K);

/// P v with P = antidiag(1, −1, 1).
Vec3 MirrorAxes(const Vec3& v);
/// (P K P, P b, P k2): z-first parameters to the x-first parameters of the mirrored problem and
/// back (an involution).
ModelParameters MirrorAxes(const ModelParameters& params);

/// The slots of the flat parameter vector in a frame (model.hpp order for x-first, the orders above
/// for z-first and platform).
const std::vector<ParameterSlot>& ParameterSlots(ModelKind kind, Frame frame);
/// d with θ_z-first = diag(d) θ_mirrored, slot by slot (entries ±1): a covariance of the mirrored
/// problem becomes diag(d) C diag(d).
Eigen::VectorXd MirrorSigns(ModelKind kind);

/// Off-diagonal misalignment entries of T = K with unit rows, named for the frame:
/// x-first τ_yx, τ_zx, τ_zy (T(1,0), T(2,0), T(2,1)); z-first τ_xy, τ_xz, τ_yz (T(0,1), T(0,2),
/// T(1,2)); platform the six angles of paper 003 eq. (5), C_p^a = [[1, β_xz, −β_xy], [−β_yz, 1,
/// β_yx], [β_zy, −β_zx, 1]] read from T: β_xz = T(0,1), β_xy = −T(0,2), β_yz = −T(1,0), β_yx =
/// T(1,2), β_zy = T(2,0), β_zx = −T(2,1) (small angles; T's rows are unit vectors where eq. (5)
/// has unit diagonal entries, a second-order difference).
struct Misalignment {
  std::vector<std::string_view> names;
  Eigen::VectorXd rad;
};
Misalignment MisalignmentOf(const Mat33& K, Frame frame);

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
