#pragma once
// The orientation-free problem with parameters that follow temperature (thermal.hpp): maximum
// likelihood over the thermal coefficients and the directions at once,
//     min J = Σ_k ‖p_k − μ(θ(T_k), g c_k)‖²,  |c_k| = 1,
// by the least-squares driver (least_squares.hpp), x the thermal flat vector and each direction a
// per-position block moved in its tangent plane; the directions profile out of the information
// as in calibrate.hpp.

#include <vector>

#include <Eigen/Core>

#include "accelcal/calibration_types.hpp"
#include "accelcal/thermal.hpp"
#include "solvers/information_row.hpp"
#include "solvers/least_squares.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

class ThermalProblem : public LeastSquaresProblem {
 public:
  /// `temperatures_c`: T_k of each reading [°C].
  ThermalProblem(const Problem& problem, const ThermalDegrees& degrees, double t_ref_c,
                 const std::vector<double>& temperatures_c);
  int GlobalSize() const override { return static_cast<int>(slots_.size()); }
  int NumBlocks() const override { return problem_.positions(); }
  int LocalSize(int /*block*/) const override { return 2; }
  Eigen::VectorXd PlusLocal(int block, const Eigen::VectorXd& y,
                            const Eigen::VectorXd& delta) const override;
  bool Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                Eigen::MatrixXd* J_y) const override;

  ThermalParameters Params(const Eigen::VectorXd& x) const;

 private:
  const Problem& problem_;
  ThermalDegrees degrees_;
  double t_ref_c_;
  std::vector<ThermalSlot> slots_;
  std::vector<double> dT_;  ///< T_k − T_ref [K]
};

struct ThermalFit {
  ThermalParameters params;
  std::vector<Vec3> dirs;
  LeastSquaresSummary summary;
  /// At the solution: the rows u_k (m × GlobalSize), the unit normals n_k, S⁻¹ (empty when S is
  /// singular), and each position's residual p_k − μ(θ(T_k), g c_k) [raw].
  Eigen::MatrixXd U;
  std::vector<Vec3> normals;
  Eigen::MatrixXd S_inverse;
  std::vector<Vec3> residuals;
};

/// Solves from `start` (its degrees and T_ref are the fit's) and `dirs`, by the joint method's
/// limits (CalibrationOptions::Joint).
ThermalFit SolveThermal(const Problem& problem, const std::vector<double>& temperatures_c,
                        const ThermalParameters& start, const std::vector<Vec3>& dirs,
                        const CalibrationOptions::Joint& joint);

}  // namespace accelcal::internal
