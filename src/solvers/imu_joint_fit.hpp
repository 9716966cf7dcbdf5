#pragma once
// The accelerometer and the gyroscope in one maximum-likelihood problem (issue 18): the
// accelerometer's parameters θ_a, the gyroscope's θ_g and the gravity direction c_k of every still
// position, from three groups of residuals, each whitened by its own noise:
//
//   - each position's mean accelerometer reading, r = (p_k − μ(θ_a, g c_k)) / σ_a (model.hpp's
//     forward model; σ_a per axis);
//   - each position's mean rate, r = (ω̄_k − b_g − G g c_k) / σ_ω,k (gyro_fit.hpp);
//   - each turn, r = L Bᵀ (v × c_j) (gyro_fit.hpp's MotionResidual), now with c_i and c_j free.
//
// The specific force during a turn (the g-sensitivity's f there) is the start accelerometer
// calibration's, held: a second-order effect of a small term. θ_a is in the slots of the
// calibration's frame (frame.hpp), which fixes the body frame's rotation: the gyroscope's K_g is
// then determined in full by the turns. All parameters are global to the driver (the turns couple
// two positions, so the directions cannot be eliminated block by block); the problem is small
// (about 2m + 33 for m positions).

#include <vector>

#include "accelcal/frame.hpp"
#include "accelcal/model.hpp"
#include "solvers/gyro_fit.hpp"
#include "solvers/least_squares.hpp"

namespace accelcal::internal {

struct ImuJointData {
  GyroFitData gyro;                ///< directions: the start; stills' f unused (g c_k is)
  std::vector<Vec3> accel_means;   ///< p_k, one per position
  std::vector<Vec3> accel_sigmas;  ///< σ_a of each p_k per axis
  std::vector<bool> accel_used;    ///< false: position k's accelerometer reading left out
  ModelKind accel_model = ModelKind::kLinear;
  Frame frame = Frame::kXFirst;  ///< x-first or z-first
  double gravity = 1;
};

struct ImuJointFit {
  ModelParameters accel;
  GyroParameters gyro;
  std::vector<Vec3> directions;
  LeastSquaresSummary summary;  ///< covariance: (θ_a, θ_g, tangent of each c_k)
  int accel_parameters = 0, gyro_parameters = 0;
};

ImuJointFit FitImuJoint(const ImuJointData& data, const ModelParameters& accel_start,
                        const GyroParameters& gyro_start, const LeastSquaresOptions& options);

/// For each motion, the joint fit without it to first order from the converged `fit`
/// (LeaveOneBlockOut, least_squares.hpp); summaries empty.
std::vector<ImuJointFit> HeldOutMotionFits(const ImuJointData& data, const ImuJointFit& fit);
/// The same for each position's accelerometer reading (a position left out of the fit keeps the
/// full fit).
std::vector<ImuJointFit> HeldOutPositionFits(const ImuJointData& data, const ImuJointFit& fit);

/// The three groups' sums of squared residuals (accelerometer, stills, turns) at a fit.
struct GroupCosts {
  double accel = 0, stills = 0, turns = 0;
};
GroupCosts JointGroupCosts(const ImuJointData& data, const ImuJointFit& fit);
/// The redundancy n_G − Σ_G h_k of each group at a converged `fit` (BlockLeverages,
/// least_squares.hpp): what its χ² is expected to be under the model.
GroupCosts JointGroupRedundancy(const ImuJointData& data, const ImuJointFit& fit);

}  // namespace accelcal::internal
