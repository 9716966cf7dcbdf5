#include "accelcal/frame.hpp"

#include <array>

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace accelcal {

namespace {

// Signs of P = antidiag(1, −1, 1): P(i, 2 − i) = kSign[i].
constexpr std::array<double, 3> kSign = {1.0, -1.0, 1.0};

// The z-first slot of an x-first (mirrored-problem) slot: row and column reflected.
ParameterSlot Mirrored(const ParameterSlot& s, std::string_view name) {
  const int col = s.group == ParameterGroup::kK ? 2 - s.col : 0;
  return {s.group, 2 - s.row, col, name};
}

}  // namespace

std::string_view ToString(Frame frame) { return frame == Frame::kXFirst ? "x-first" : "z-first"; }

std::optional<Frame> FrameFromString(std::string_view text) {
  if (text == "x-first") return Frame::kXFirst;
  if (text == "z-first") return Frame::kZFirst;
  return std::nullopt;
}

Frame FrameOf(const Mat33& K) {
  const bool lower = K(0, 1) == 0 && K(0, 2) == 0 && K(1, 2) == 0;
  return lower ? Frame::kXFirst : Frame::kZFirst;
}

Vec3 MirrorAxes(const Vec3& v) { return Vec3(v(2), -v(1), v(0)); }

ModelParameters MirrorAxes(const ModelParameters& params) {
  ModelParameters out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out.K(i, j) = kSign[i] * kSign[j] * params.K(2 - i, 2 - j);
  }
  out.bias = MirrorAxes(params.bias);
  out.k2 = MirrorAxes(params.k2);
  return out;
}

const std::vector<ParameterSlot>& ParameterSlots(ModelKind kind, Frame frame) {
  if (frame == Frame::kXFirst) return ParameterSlots(kind);
  static const std::vector<std::string_view> names = {
      "K_zz", "b_z", "k2_z", "K_yz", "K_yy", "b_y", "k2_y", "K_xz", "K_xy", "K_xx", "b_x", "k2_x"};
  static const std::vector<ParameterSlot> quadratic = [] {
    std::vector<ParameterSlot> slots;
    const auto& x_first = ParameterSlots(ModelKind::kQuadratic);
    for (std::size_t i = 0; i < x_first.size(); ++i)
      slots.push_back(Mirrored(x_first[i], names[i]));
    return slots;
  }();
  static const std::vector<ParameterSlot> linear = [] {
    std::vector<ParameterSlot> slots;
    for (const ParameterSlot& s : quadratic) {
      if (s.group != ParameterGroup::kK2) slots.push_back(s);
    }
    return slots;
  }();
  return kind == ModelKind::kLinear ? linear : quadratic;
}

Eigen::VectorXd MirrorSigns(ModelKind kind) {
  const auto& slots = ParameterSlots(kind);
  Eigen::VectorXd d(static_cast<Eigen::Index>(slots.size()));
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const double row_sign = kSign[static_cast<std::size_t>(slots[i].row)];
    const double col_sign =
        slots[i].group == ParameterGroup::kK ? kSign[static_cast<std::size_t>(slots[i].col)] : 1.0;
    d(static_cast<Eigen::Index>(i)) = row_sign * col_sign;
  }
  return d;
}

Misalignment MisalignmentOf(const Mat33& K, Frame frame) {
  Mat33 T;
  for (int i = 0; i < 3; ++i) T.row(i) = K.row(i) / K.row(i).norm();
  if (frame == Frame::kXFirst)
    return {{"tau_yx", "tau_zx", "tau_zy"}, Vec3(T(1, 0), T(2, 0), T(2, 1))};
  return {{"tau_xy", "tau_xz", "tau_yz"}, Vec3(T(0, 1), T(0, 2), T(1, 2))};
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
