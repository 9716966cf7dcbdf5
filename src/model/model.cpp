#include "accelcal/model.hpp"
namespace accelcal {

std::string_view ToString(ModelKind kind) { return NameOf(kind); }

std::optional<ModelKind> ModelKindFromString(std::string_view text) {
  return FromName<ModelKind>(text);
}

const std::vector<ParameterSlot>& ParameterSlots(ModelKind kind) {
  using G = ParameterGroup;
  static const std::vector<ParameterSlot> quadratic = {
      {G::kK, 0, 0, "K_xx"},  {G::kBias, 0, 0, "b_x"}, {G::kK2, 0, 0, "k2_x"},
      {G::kK, 1, 0, "K_yx"},  {G::kK, 1, 1, "K_yy"},   {G::kBias, 1, 0, "b_y"},
      {G::kK2, 1, 0, "k2_y"}, {G::kK, 2, 0, "K_zx"},   {G::kK, 2, 1, "K_zy"},
      {G::kK, 2, 2, "K_zz"},  {G::kBias, 2, 0, "b_z"}, {G::kK2, 2, 0, "k2_z"}};
  static const std::vector<ParameterSlot> linear = [] {
    std::vector<ParameterSlot> slots;
    for (const ParameterSlot& s : quadratic) {
      if (s.group != G::kK2) slots.push_back(s);
    }
    return slots;
  }();
  return kind == ModelKind::kLinear ? linear : quadratic;
}

const std::vector<int>& ActiveColumns(ModelKind kind) {
  static const std::vector<int> quadratic = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  static const std::vector<int> linear = {0, 1, 3, 4, 5, 7, 8, 9, 10};
  return kind == ModelKind::kLinear ? linear : quadratic;
}

double SlotRegressor(const ParameterSlot& s, const Vec3& f) {
  switch (s.group) {
    case ParameterGroup::kK:
      return f(s.col);
    case ParameterGroup::kBias:
      return 1.0;
    case ParameterGroup::kK2:
      break;
  }
  return f(s.row) * f(s.row);
}

double& SlotRef(ModelParameters& p, const ParameterSlot& s) {
  switch (s.group) {
    case ParameterGroup::kK:
      return p.K(s.row, s.col);
    case ParameterGroup::kBias:
      return p.bias(s.row);
    case ParameterGroup::kK2:
      break;
  }
  return p.k2(s.row);
}

Eigen::VectorXd Pack(const ModelParameters& params, ModelKind kind) {
  return Pack(params, ParameterSlots(kind));
}

ModelParameters Unpack(const Eigen::VectorXd& theta, ModelKind kind) {
  return Unpack(theta, ParameterSlots(kind));
}

Eigen::VectorXd Pack(const ModelParameters& params, const std::vector<ParameterSlot>& slots) {
  Eigen::VectorXd theta(static_cast<Eigen::Index>(slots.size()));
  ModelParameters copy = params;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    theta(static_cast<Eigen::Index>(i)) = SlotRef(copy, slots[i]);
  }
  return theta;
}

ModelParameters Unpack(const Eigen::VectorXd& theta, const std::vector<ParameterSlot>& slots) {
  ModelParameters params;
  params.K.setZero();
  for (std::size_t i = 0; i < slots.size(); ++i) {
    SlotRef(params, slots[i]) = theta(static_cast<Eigen::Index>(i));
  }
  return params;
}

}  // namespace accelcal
