#pragma once
// One fit of the orientation-free problem with its statistics: the solve (solvers/solve.hpp),
// observability at the solution, residuals, covariance (from the residuals or the readings'
// sigmas) and the screening statistics of OutlierOptions, in the frame of CalibrationOptions.

#include <vector>

#include "accelcal/calibration_types.hpp"
#include "statistics/outliers.hpp"

namespace accelcal::internal {

/// A fit and, when the options ask for it and the fit converged, its outlier statistics.
struct Fit {
  CalibrationResult result;
  internal::Screening screening;
};

/// The fit in the requested frame (frame.hpp): z-first is the x-first fit of the mirrored
/// readings (the outlier statistics do not depend on the gauge).
Fit CalibrateInFrame(const std::vector<Vec3>& readings, const CalibrationOptions& options);

/// Throws std::invalid_argument unless `sigmas` (CalibrationOptions::reading_sigmas and its
/// twins) is empty or holds one finite, positive 3-vector per reading.
void CheckReadingSigmas(const std::vector<Vec3>& sigmas, std::size_t readings);
/// Throws DataError naming the first reading that repeats an earlier one exactly (duplicated
/// rows, a file concatenated with itself): the degrees of freedom count distinct positions.
void CheckDistinctReadings(const std::vector<Vec3>& readings);

/// `options` for the readings at indices `keep` only: their reading_sigmas and position times, and
/// the bias drift's basis of all the positions (the same knots and reference time).
CalibrationOptions OptionsForPositions(const CalibrationOptions& options,
                                       const std::vector<int>& keep);

/// `fit`, of the readings at indices `keep`, spread back over all `readings`: a left-out position
/// gets its direction and residual under the fit. `times_s`: every reading's time, for a fit with
/// a drifting bias (its drift then lists them all).
void SpreadOverAllPositions(const std::vector<Vec3>& readings, const std::vector<int>& keep,
                            const std::vector<double>& times_s, CalibrationResult* fit);

}  // namespace accelcal::internal
