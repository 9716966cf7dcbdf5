#pragma once
/// @file thermal.hpp
/// Parameters that follow temperature (issue 21): the model of model.hpp with each parameter
/// group a polynomial in the temperature's difference from a reference,
///     θ(T) = Σ_{d=0}^{D} θ_d ΔT^d,   ΔT = T − T_ref [K],
///     p = K(T) f + b(T) + k2(T) ∘ f²,
/// the degree D_g chosen per group g (K: scale factors and misalignments; b; k2). θ_0 is the
/// calibration at T_ref in model.hpp's units; θ_d is in those units per K^d. K(T) keeps the
/// gauge of K (lower-triangular, x-first): a rotation of the sensor that changed with temperature
/// would be taken up by the positions' free directions, so only the triangular part is observable.
///
/// Flat order: θ_0 in the model's order (NumParameters), then for d = 1 … D the model's slots of
/// the groups whose degree is at least d, in the model's order (ThermalSlots).

#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/gyro_model.hpp"
#include "accelcal/model.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// The polynomial degree of each parameter group in ΔT (0: constant over temperature).
struct ThermalDegrees {
  int K = 0;     ///< scale factors and misalignments
  int bias = 0;  ///< b
  int k2 = 0;    ///< squared coefficients (the quadratic model only)

  int Of(ParameterGroup group) const;
  int Max() const;
  /// "K:1 b:2" ("k2:d" added when k2 varies): each group and its degree.
  std::string ToString() const;
  friend bool operator==(const ThermalDegrees& a, const ThermalDegrees& b) {
    return a.K == b.K && a.bias == b.bias && a.k2 == b.k2;
  }
};

/// Largest degree a group may have: a cubic in temperature is already more than a few
/// temperatures can support.
inline constexpr int kMaxThermalDegree = 3;

/// A slot of the thermal flat vector: the model's slot and the power of ΔT it multiplies.
struct ThermalSlot {
  ParameterSlot slot;
  int degree = 0;
};

/// The flat vector's slots for `model` and `degrees` (file comment's order).
std::vector<ThermalSlot> ThermalSlots(ModelKind model, const ThermalDegrees& degrees);
/// A slot's name in files and plans: the model's ("K_xx") with "*dT^d" for degree d > 0.
std::string ThermalSlotName(const ThermalSlot& slot);

struct ThermalParameters {
  double t_ref_c = 0;  ///< T_ref [°C]
  ThermalDegrees degrees;
  /// θ_d for d = 0 … degrees.Max(): [model units per K^d]; a group's entries above its degree
  /// are zero.
  std::vector<ModelParameters> coefficients;

  /// θ(T) [model units].
  ModelParameters At(double t_c) const;
};

/// The flat vector of `params` (ThermalSlots order), and back. Unpack zeroes what the slots do
/// not hold.
Eigen::VectorXd Pack(const ThermalParameters& params, ModelKind model);
ThermalParameters UnpackThermal(const Eigen::VectorXd& x, ModelKind model,
                                const ThermalDegrees& degrees, double t_ref_c);
/// `at_ref` (x-first) at every temperature: θ_0 its entries that `model` holds, the temperature
/// coefficients of `degrees` zero (a thermal fit's start, a plan's device).
ThermalParameters ConstantOverTemperature(const ModelParameters& at_ref, ModelKind model,
                                          const ThermalDegrees& degrees, double t_ref_c);

/// The gyroscope's offsets over temperature, beside the accelerometer's model above: the bias of
/// gyro_model.hpp as a polynomial in ΔT = T − T_ref, the rest of the gyroscope's model constant,
///     b_g(T) = b_g + Σ_{d=1}^{D} b_d ΔT^d,
/// b_g the calibration's bias (at T_ref), b_d [gyro raw per K^d]. This is what PX4's TC_G and
/// ArduPilot's INS_TCALn_GYR hold; a gyroscope's scale moves too little with temperature to be
/// seen by the turns of a tumble (MEMS: 0.01-0.03 %/K, against a turn's 0.1 % resolution).
struct GyroThermalBias {
  double t_ref_c = 0;  ///< T_ref [°C]
  /// b_d for d = 1 … D [gyro raw per K^d]; empty: the offsets do not follow temperature.
  std::vector<Vec3> coefficients;
  /// Covariance of (b_1x, b_1y, b_1z, b_2x, …), 3D x 3D.
  Eigen::MatrixXd covariance;

  int degree() const { return static_cast<int>(coefficients.size()); }
  /// Σ_{d≥1} b_d (T − T_ref)^d: how far the offset at `t_c` lies from the calibration's b_g
  /// [gyro raw].
  Vec3 OffsetChange(double t_c) const;
};

}  // namespace accelcal
