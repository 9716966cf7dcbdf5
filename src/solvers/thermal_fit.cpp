// The joint fit with parameters that follow temperature (thermal_fit.hpp).
#include "solvers/thermal_fit.hpp"

#include <cmath>
#include <stdexcept>

namespace accelcal::internal {

ThermalProblem::ThermalProblem(const Problem& problem, const ThermalDegrees& degrees,
                               double t_ref_c, const std::vector<double>& temperatures_c)
    : problem_(problem),
      degrees_(degrees),
      t_ref_c_(t_ref_c),
      slots_(ThermalSlots(problem.model, degrees)) {
  if (temperatures_c.size() != problem.readings.size()) {
    throw std::invalid_argument("one temperature per reading is needed");
  }
  for (double t : temperatures_c) dT_.push_back(t - t_ref_c);
}

Eigen::VectorXd ThermalProblem::PlusLocal(int /*block*/, const Eigen::VectorXd& y,
                                          const Eigen::VectorXd& delta) const {
  const Vec3 c = y;
  return Retract(c, TangentBasis(c), Eigen::Vector2d(delta));
}

bool ThermalProblem::Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                              Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                              Eigen::MatrixXd* J_y) const {
  const auto k = static_cast<std::size_t>(block);
  const ModelParameters params = Params(x).At(t_ref_c_ + dT_[k]);
  const Vec3 c = y;
  const Vec3 f = problem_.gravity * c;
  Mat33 J_f;
  *residual = problem_.readings[k] - PredictRaw(params, f, &J_f);
  if (J_x != nullptr) {
    // ∂μ/∂θ_d = ΔT^d ∂μ/∂θ.
    J_x->setZero(3, GlobalSize());
    for (std::size_t s = 0; s < slots_.size(); ++s) {
      const ParameterSlot& slot = slots_[s].slot;
      (*J_x)(slot.row, static_cast<Eigen::Index>(s)) =
          -SlotRegressor(slot, f) * std::pow(dT_[k], slots_[s].degree);
    }
  }
  if (J_y != nullptr) *J_y = -(J_f * problem_.gravity) * TangentBasis(c);
  return residual->allFinite();
}

ThermalParameters ThermalProblem::Params(const Eigen::VectorXd& x) const {
  return UnpackThermal(x, problem_.model, degrees_, t_ref_c_);
}

ThermalFit SolveThermal(const Problem& problem, const std::vector<double>& temperatures_c,
                        const ThermalParameters& start, const std::vector<Vec3>& dirs,
                        const CalibrationOptions::Joint& joint) {
  const ThermalProblem lsq(problem, start.degrees, start.t_ref_c, temperatures_c);
  const int m = problem.positions();
  const ModelParameters at_ref = start.At(start.t_ref_c);
  LeastSquaresState state;
  state.x = Pack(start, problem.model);
  for (const Vec3& c : dirs) state.y.emplace_back(c.normalized());

  LeastSquaresOptions options;
  options.max_iterations = joint.max_iterations;
  options.initial_damping = joint.initial_damping;
  options.function_tolerance = joint.function_tolerance;
  options.step_tolerance = joint.parameter_tolerance * SignalAmplitude(at_ref, problem.gravity);
  options.zero_residual_cost = ZeroResidualCost(problem, at_ref);
  options.compute_covariance = true;

  ThermalFit fit;
  fit.summary = SolveLeastSquares(lsq, options, &state);
  fit.params = lsq.Params(state.x);
  for (int k = 0; k < m; ++k) fit.dirs.emplace_back(state.y[static_cast<std::size_t>(k)]);
  fit.S_inverse = fit.summary.information_inverse;
  fit.U.resize(m, lsq.GlobalSize());
  fit.normals.resize(static_cast<std::size_t>(m));
  fit.residuals.resize(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    fit.U.row(k) =
        InformationRow(lsq, state.x, k, state.y[i], &fit.normals[i], &fit.residuals[i]).transpose();
  }
  return fit;
}

}  // namespace accelcal::internal
