#pragma once
/// @file sensor_parameters.hpp
/// The parameters of every sensor's model listed alike: each in its model's flat order (the
/// covariance's), with its name as the file's `parameter_order` writes it, its role, which sets
/// its unit, and its value. What lists a sensor's parameters (the acceptance quantities, the
/// report's tables, Python's dicts) does so through this, once for every sensor; a new sensor's
/// model gives one ListParameters.

#include <string>
#include <string_view>
#include <vector>

#include "accelcal/frame.hpp"
#include "accelcal/gyro_model.hpp"
#include "accelcal/model.hpp"

namespace accelcal {

/// What a parameter is to its sensor's raw reading r of a quantity q (specific force, rate).
enum class ParameterRole {
  kScale,             ///< ∂r/∂q: raw per q's unit (K, K_g)
  kOffset,            ///< r at q = 0: raw (b, b_g)
  kSquare,            ///< ∂r/∂q²: raw per (q's unit)² (k2)
  kCrossSensitivity,  ///< ∂r/∂ another sensor's quantity: raw per its unit (G, the gyro's
                      ///< g-sensitivity)
};

struct SensorParameter {
  std::string_view name;  ///< as in the file's `parameter_order` ("K_yx", "Kg_xy", "G_zx")
  ParameterRole role;
  int axis = 0;  ///< the output axis it belongs to (its row: 0 x, 1 y, 2 z)
  double value = 0;
};

/// The names and the values of a list, in its order.
std::vector<std::string> ParameterNames(const std::vector<SensorParameter>& list);
Eigen::VectorXd ParameterValues(const std::vector<SensorParameter>& list);

/// The accelerometer's parameters in the order of ParameterSlots(model, frame).
std::vector<SensorParameter> ListParameters(const ModelParameters& params, ModelKind model,
                                            Frame frame);
/// The gyroscope's, in the order of GyroParameterSlots(model).
std::vector<SensorParameter> ListParameters(const GyroParameters& params, GyroModelKind model);

/// A parameter's unit, for a sensor whose raw unit is `raw` and whose quantity is in `quantity`
/// ("m/s2", "rad/s"); `other`: the other sensor's quantity a cross-sensitivity is to.
std::string ParameterUnit(ParameterRole role, const std::string& raw, const std::string& quantity,
                          const std::string& other);

}  // namespace accelcal
