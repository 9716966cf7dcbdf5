// Every sensor's parameters listed alike (sensor_parameters.hpp).
#include "accelcal/sensor_parameters.hpp"

namespace accelcal {

std::vector<SensorParameter> ListParameters(const ModelParameters& params, ModelKind model,
                                            Frame frame) {
  const std::vector<ParameterSlot>& slots = ParameterSlots(model, frame);
  const Eigen::VectorXd values = Pack(params, slots);
  std::vector<SensorParameter> out;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const ParameterGroup g = slots[i].group;
    out.push_back({slots[i].name,
                   g == ParameterGroup::kK      ? ParameterRole::kScale
                   : g == ParameterGroup::kBias ? ParameterRole::kOffset
                                                : ParameterRole::kSquare,
                   slots[i].row, values(static_cast<Eigen::Index>(i))});
  }
  return out;
}

std::vector<SensorParameter> ListParameters(const GyroParameters& params, GyroModelKind model) {
  const std::vector<GyroParameterSlot>& slots = GyroParameterSlots(model);
  const Eigen::VectorXd values = Pack(params, model);
  std::vector<SensorParameter> out;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const GyroParameterGroup g = slots[i].group;
    out.push_back({slots[i].name,
                   g == GyroParameterGroup::kK      ? ParameterRole::kScale
                   : g == GyroParameterGroup::kBias ? ParameterRole::kOffset
                                                    : ParameterRole::kCrossSensitivity,
                   slots[i].row, values(static_cast<Eigen::Index>(i))});
  }
  return out;
}

std::vector<std::string> ParameterNames(const std::vector<SensorParameter>& list) {
  std::vector<std::string> names;
  for (const SensorParameter& p : list) names.emplace_back(p.name);
  return names;
}

Eigen::VectorXd ParameterValues(const std::vector<SensorParameter>& list) {
  Eigen::VectorXd values(static_cast<Eigen::Index>(list.size()));
  for (std::size_t i = 0; i < list.size(); ++i)
    values(static_cast<Eigen::Index>(i)) = list[i].value;
  return values;
}

std::string ParameterUnit(ParameterRole role, const std::string& raw, const std::string& quantity,
                          const std::string& other) {
  switch (role) {
    case ParameterRole::kScale:
      return raw + " per " + quantity;
    case ParameterRole::kOffset:
      return raw;
    case ParameterRole::kSquare:
      return raw + " per (" + quantity + ")^2";
    case ParameterRole::kCrossSensitivity:
      return raw + " per " + other;
  }
  return raw;
}

}  // namespace accelcal
