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

std::string_view ToString(Frame frame) { return NameOf(frame); }

std::optional<Frame> FrameFromString(std::string_view text) { return FromName<Frame>(text); }

Frame FrameOf(const Mat33& K) {
  const bool lower = K(0, 1) == 0 && K(0, 2) == 0 && K(1, 2) == 0;
  const bool upper = K(1, 0) == 0 && K(2, 0) == 0 && K(2, 1) == 0;
  return lower ? Frame::kXFirst : upper ? Frame::kZFirst : Frame::kPlatform;
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

namespace {

// The linear model's slots: the quadratic model's without k2.
std::vector<ParameterSlot> WithoutSquaredTerms(const std::vector<ParameterSlot>& quadratic) {
  std::vector<ParameterSlot> slots;
  for (const ParameterSlot& s : quadratic) {
    if (s.group != ParameterGroup::kK2) slots.push_back(s);
  }
  return slots;
}

const std::vector<ParameterSlot>& PlatformSlots(ModelKind kind) {
  static const std::vector<ParameterSlot> quadratic = {
      {ParameterGroup::kK, 0, 0, "K_xx"},   {ParameterGroup::kK, 0, 1, "K_xy"},
      {ParameterGroup::kK, 0, 2, "K_xz"},   {ParameterGroup::kBias, 0, 0, "b_x"},
      {ParameterGroup::kK2, 0, 0, "k2_x"},  {ParameterGroup::kK, 1, 0, "K_yx"},
      {ParameterGroup::kK, 1, 1, "K_yy"},   {ParameterGroup::kK, 1, 2, "K_yz"},
      {ParameterGroup::kBias, 1, 0, "b_y"}, {ParameterGroup::kK2, 1, 0, "k2_y"},
      {ParameterGroup::kK, 2, 0, "K_zx"},   {ParameterGroup::kK, 2, 1, "K_zy"},
      {ParameterGroup::kK, 2, 2, "K_zz"},   {ParameterGroup::kBias, 2, 0, "b_z"},
      {ParameterGroup::kK2, 2, 0, "k2_z"}};
  static const std::vector<ParameterSlot> linear = WithoutSquaredTerms(quadratic);
  return kind == ModelKind::kLinear ? linear : quadratic;
}

}  // namespace

const std::vector<ParameterSlot>& ParameterSlots(ModelKind kind, Frame frame) {
  if (frame == Frame::kXFirst) return ParameterSlots(kind);
  if (frame == Frame::kPlatform) return PlatformSlots(kind);
  static const std::vector<std::string_view> names = {
      "K_zz", "b_z", "k2_z", "K_yz", "K_yy", "b_y", "k2_y", "K_xz", "K_xy", "K_xx", "b_x", "k2_x"};
  static const std::vector<ParameterSlot> quadratic = [] {
    std::vector<ParameterSlot> slots;
    const auto& x_first = ParameterSlots(ModelKind::kQuadratic);
    for (std::size_t i = 0; i < x_first.size(); ++i)
      slots.push_back(Mirrored(x_first[i], names[i]));
    return slots;
  }();
  static const std::vector<ParameterSlot> linear = WithoutSquaredTerms(quadratic);
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
  switch (frame) {
    case Frame::kXFirst:
      return {{"tau_yx", "tau_zx", "tau_zy"}, Vec3(T(1, 0), T(2, 0), T(2, 1))};
    case Frame::kZFirst:
      return {{"tau_xy", "tau_xz", "tau_yz"}, Vec3(T(0, 1), T(0, 2), T(1, 2))};
    case Frame::kPlatform:
      break;
  }
  Eigen::VectorXd beta(6);
  beta << T(0, 1), -T(0, 2), -T(1, 0), T(1, 2), T(2, 0), -T(2, 1);
  return {{"beta_xz", "beta_xy", "beta_yz", "beta_yx", "beta_zy", "beta_zx"}, beta};
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
