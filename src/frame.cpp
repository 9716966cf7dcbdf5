#include "accelcal/frame.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace accelcal {

std::string_view ToString(Frame frame) { return frame == Frame::kXFirst ? "x-first" : "z-first"; }

std::optional<Frame> FrameFromString(std::string_view text) {
  if (text == "x-first") return Frame::kXFirst;
  if (text == "z-first") return Frame::kZFirst;
  return std::nullopt;
}

FrameChange ChangeFrame(const Mat33& K, Frame frame) {
  const Mat33 S = K * K.transpose();
  FrameChange change;
  if (frame == Frame::kXFirst) {
    change.K = S.llt().matrixL();
  } else {
    // With E the exchange matrix (E = E⁻¹), E S E = L Lᵀ gives S = (E L E)(E L E)ᵀ, and E L E is
    // upper-triangular with the same (positive) diagonal entries in reverse order.
    Mat33 E = Mat33::Zero();
    E(0, 2) = E(1, 1) = E(2, 0) = 1.0;
    const Mat33 L = Mat33((E * S * E).llt().matrixL());
    change.K = E * L * E;
  }
  change.Q_old_new = K.inverse() * change.K;
  return change;
}

}  // namespace accelcal
