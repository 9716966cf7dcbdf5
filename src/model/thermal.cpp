// Parameters that follow temperature (thermal.hpp).
#include "accelcal/thermal.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace accelcal {

int ThermalDegrees::Of(ParameterGroup group) const {
  switch (group) {
    case ParameterGroup::kK:
      return K;
    case ParameterGroup::kBias:
      return bias;
    case ParameterGroup::kK2:
      return k2;
  }
  return 0;
}

int ThermalDegrees::Max() const { return std::max(K, std::max(bias, k2)); }

std::string ThermalDegrees::ToString() const {
  return "K:" + std::to_string(K) + " b:" + std::to_string(bias) +
         (k2 > 0 ? " k2:" + std::to_string(k2) : std::string());
}

std::string ThermalSlotName(const ThermalSlot& slot) {
  return std::string(slot.slot.name) +
         (slot.degree > 0 ? "*dT^" + std::to_string(slot.degree) : std::string());
}

std::vector<ThermalSlot> ThermalSlots(ModelKind model, const ThermalDegrees& degrees) {
  for (int d : {degrees.K, degrees.bias, degrees.k2}) {
    if (d < 0 || d > kMaxThermalDegree) {
      throw std::invalid_argument("a thermal degree must be from 0 to " +
                                  std::to_string(kMaxThermalDegree) + ", not " + std::to_string(d));
    }
  }
  if (model == ModelKind::kLinear && degrees.k2 > 0) {
    throw std::invalid_argument("the linear model has no squared terms to vary with temperature");
  }
  std::vector<ThermalSlot> slots;
  for (int d = 0; d <= degrees.Max(); ++d) {
    for (const ParameterSlot& s : ParameterSlots(model)) {
      if (d == 0 || degrees.Of(s.group) >= d) slots.push_back({s, d});
    }
  }
  return slots;
}

Vec3 GyroThermalBias::OffsetChange(double t_c) const {
  const double dT = t_c - t_ref_c;
  Vec3 out = Vec3::Zero();
  double power = 1;
  for (const Vec3& b : coefficients) {
    power *= dT;
    out += power * b;
  }
  return out;
}

ModelParameters ThermalParameters::At(double t_c) const {
  const double dT = t_c - t_ref_c;
  ModelParameters out = coefficients.at(0);
  double power = 1;
  for (std::size_t d = 1; d < coefficients.size(); ++d) {
    power *= dT;
    out.K += power * coefficients[d].K;
    out.bias += power * coefficients[d].bias;
    out.k2 += power * coefficients[d].k2;
  }
  return out;
}

Eigen::VectorXd Pack(const ThermalParameters& params, ModelKind model) {
  const std::vector<ThermalSlot> slots = ThermalSlots(model, params.degrees);
  Eigen::VectorXd x(static_cast<Eigen::Index>(slots.size()));
  for (std::size_t i = 0; i < slots.size(); ++i) {
    ModelParameters p = params.coefficients.at(static_cast<std::size_t>(slots[i].degree));
    x(static_cast<Eigen::Index>(i)) = SlotRef(p, slots[i].slot);
  }
  return x;
}

ThermalParameters UnpackThermal(const Eigen::VectorXd& x, ModelKind model,
                                const ThermalDegrees& degrees, double t_ref_c) {
  const std::vector<ThermalSlot> slots = ThermalSlots(model, degrees);
  if (x.size() != static_cast<Eigen::Index>(slots.size())) {
    throw std::invalid_argument("a thermal vector of " + std::to_string(x.size()) +
                                " entries for " + std::to_string(slots.size()) + " slots");
  }
  ThermalParameters out;
  out.t_ref_c = t_ref_c;
  out.degrees = degrees;
  ModelParameters zero;
  zero.K.setZero();
  out.coefficients.assign(static_cast<std::size_t>(degrees.Max() + 1), zero);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    SlotRef(out.coefficients[static_cast<std::size_t>(slots[i].degree)], slots[i].slot) =
        x(static_cast<Eigen::Index>(i));
  }
  return out;
}

ThermalParameters ConstantOverTemperature(const ModelParameters& at_ref, ModelKind model,
                                          const ThermalDegrees& degrees, double t_ref_c) {
  Eigen::VectorXd x =
      Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ThermalSlots(model, degrees).size()));
  x.head(NumParameters(model)) = Pack(at_ref, model);
  return UnpackThermal(x, model, degrees, t_ref_c);
}

}  // namespace accelcal
