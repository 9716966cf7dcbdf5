#pragma once
/// @file orientation_file.hpp
/// Files of orientations, one position per line: planned positions (design, simulate) and, for
/// known-orientation calibration, measured ones. Three layouts, chosen by the header:
///
///   x,y,z                       unit specific-force directions c in the body frame (no header:
///                               three numbers per line are read as this)
///   roll_deg,pitch_deg[,yaw_deg] attitudes, degrees
///   qw,qx,qy,qz                 attitudes as unit quaternions (Hamilton, scalar first)
///   theta1_deg,theta2_deg,theta3_deg  gimbal angles of paper 003's three-gimbal platform, degrees:
///                               c = PlatformUp(θ) (platform_model.hpp; no attitude stored)
///
/// Attitude convention: R = Rz(yaw) Ry(pitch) Rx(roll) maps body-frame vectors to a level frame
/// whose z axis points up, so a sensor at rest senses the specific force g Rᵀ e_z:
///
///     c = Rᵀ e_z = (−sin pitch, sin roll cos pitch, cos roll cos pitch)
///
/// (level: c = +z; yaw does not change c). A frame with z down (NED) has the opposite sign on every
/// component: give its directions instead, or negate roll by 180°.
/// Delimiters: commas, tabs or runs of spaces; `#` starts a comment; blank lines are skipped.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "accelcal/types.hpp"

namespace accelcal {

enum class OrientationLayout { kDirections, kRollPitchYaw, kQuaternions, kGimbalAngles };

struct OrientationFile {
  OrientationLayout layout = OrientationLayout::kDirections;
  std::vector<Vec3> directions;               ///< unit c per position, body frame
  std::vector<Eigen::Quaterniond> attitudes;  ///< R per position (roll/pitch/yaw, quaternions)
  std::vector<std::size_t> lines;             ///< 1-based line of each position
  /// ReadOrientations: the file's size and the SHA-256 of its bytes (a calibration's provenance).
  std::uint64_t bytes = 0;
  std::string sha256;
};

/// R = Rz(yaw) Ry(pitch) Rx(roll), angles in radians.
Eigen::Quaterniond AttitudeFromRollPitchYaw(double roll_rad, double pitch_rad, double yaw_rad);
/// c = Rᵀ e_z for an attitude R (see the file comment).
Vec3 UpDirectionInBody(const Eigen::Quaterniond& body_to_level);

/// Parses the text of an orientation file; `source` names it in errors. Throws InputError (file,
/// line, reason) for anything it cannot read: unknown header, wrong column count, a number that
/// does not parse or is not finite, a direction or quaternion whose norm is more than 1e-3 from
/// 1 (both are then normalised), no positions.
OrientationFile ParseOrientations(std::string_view text, const std::string& source);
/// ParseOrientations of a file's contents.
OrientationFile ReadOrientations(const std::string& path);

}  // namespace accelcal
