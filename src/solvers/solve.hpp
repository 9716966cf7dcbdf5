#pragma once
// One solve of the orientation-free problem (calibrate.hpp) by the method of CalibrationOptions:
// the data checks, the start (ellipsoid fit or paper 000 eq. (26)), the method's iterations and,
// with few degrees of freedom, the extra starts. The statistics of the solution (covariance,
// screening) are the statistics layer's (statistics/fit.hpp).

#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibration_types.hpp"
#include "accelcal/ellipsoid_fit.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

/// Throws DataError for a non-finite reading, fewer positions than parameters, or positions in
/// one plane.
void CheckData(const std::vector<Vec3>& readings, ModelKind model);

/// Name of a 12-layout slot in the frame the user asked for.
std::string SlotName(int index, Frame frame);

/// Throws DataError naming the parameter the positions do not determine (rcond below
/// kMinInformationRcond).
void ThrowIfUnobservable(const Information& info, ModelKind model, Frame frame);

/// Where a solve starts: parameters, directions, and how they were found.
struct Start {
  ModelParameters params;
  std::vector<Vec3> dirs;
  Initialization used;
  EllipsoidFitKind fit_kind = EllipsoidFitKind::kAlgebraic;
  std::string note;
};
Start Initialise(const Problem& problem, Initialization requested,
                 const std::optional<ModelParameters>& given);

/// The iterative method of `options` from a start.
SolverOutput SolveFrom(const Problem& problem, const ModelParameters& params,
                       std::vector<Vec3> dirs, const CalibrationOptions& options);

/// With few degrees of freedom, the other starts; keeps the lowest converged cost in `out`.
void MultiStart(const Problem& problem, const CalibrationOptions& options, SolverOutput* out);

/// Estimator::kBiasCorrected: refits `out` with each reading moved inward by its expected offset
/// from the fitted surface until the shifts settle; returns the readings of the last fit
/// (bias_correction.cpp).
std::vector<Vec3> CorrectBias(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                              SolverOutput* out);

}  // namespace accelcal::internal
