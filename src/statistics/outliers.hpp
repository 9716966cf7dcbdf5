#pragma once
// The discordant-position test of calibrate.hpp (OutlierPolicy), on one converged fit.

#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

struct Screening {
  bool ran = false;            ///< false: too few positions or a singular fit (see note)
  std::vector<double> t;       ///< t_k per position of the fit (NaN: not tested, h_k ≈ 1)
  std::vector<double> e;       ///< normal residuals e_k [raw]
  double scatter = 0;          ///< s [raw]
  int degrees_of_freedom = 0;  ///< of t_k: m − P − 1
  double per_position_probability = 0;  ///< false_alarm / m (Bonferroni)
  int most_discordant = -1;             ///< index of the largest |t_k|, −1 when none was tested
  bool significant = false;  ///< its two-sided probability is below per_position_probability
  /// Some |e_k| / (s_robust √(1 − h_k)) beyond the threshold, s_robust = 1.4826 · median of
  /// |e_j| / √(1 − h_j): a scale that a few discordant positions cannot inflate, so that two of
  /// them cannot hide each other (masking) from the t test.
  bool suspicious = false;
  std::string note;  ///< why the test could not run, or which positions it could not test

  /// position = index (of the fit), not excluded; the threshold is the |t| of two-sided
  /// probability per_position_probability (computed here only: the decisions compare
  /// probabilities, one incomplete beta function each).
  OutlierFinding Finding(int index) const;
};

/// The statistics of OutlierPolicy at a converged fit, in the x-first gauge (normal residuals and
/// leverages do not depend on it): the information rows u_k and normals n_k at the solution, S⁻¹
/// (fixed parameters' block the identity), the residuals p_k − μ_k [raw], and the largest axis
/// signal |K_ii| g + |b_i| [raw] for the round-off floor.
Screening ScreenPositions(const InformationRows& rows, const Mat12& S_inverse, ModelKind model,
                          const std::vector<Vec3>& residuals, double signal,
                          double false_alarm_probability);

/// Throws std::invalid_argument unless `sigmas` (CalibrationOptions::reading_sigmas and its
/// twins) is empty or holds one finite, positive 3-vector per reading.
void CheckReadingSigmas(const std::vector<Vec3>& sigmas, std::size_t readings);
/// Throws DataError naming the first reading that repeats an earlier one exactly (duplicated
/// rows, a file concatenated with itself): the degrees of freedom count distinct positions.
void CheckDistinctReadings(const std::vector<Vec3>& readings);

/// `fit`, of the readings at indices `keep`, spread back over all `readings`: a left-out position
/// gets its direction and residual under the fit.
void SpreadOverAllPositions(const std::vector<Vec3>& readings, const std::vector<int>& keep,
                            CalibrationResult* fit);

}  // namespace accelcal::internal
