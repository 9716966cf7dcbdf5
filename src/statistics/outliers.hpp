#pragma once
// The discordant-position test of calibrate.hpp (OutlierPolicy), on one converged fit.

#include <string>
#include <vector>

#include "accelcal/calibration_types.hpp"
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

/// The same test on any fit whose positions' information rows give the leverages h_k = u_kᵀ S⁻¹ u_k
/// (P parameters in all; `what` names the model in the note when there are too few positions).
Screening ScreenWithLeverages(const std::vector<Vec3>& normals,
                              const std::vector<double>& leverages, int P, const std::string& what,
                              const std::vector<Vec3>& residuals, double signal,
                              double false_alarm_probability);

/// Calibrate's fit with the screening of OutlierOptions (Rosner's generalised ESD, calibrate.cpp
/// documents the policy): without cross-validation.
CalibrationResult CalibrateScreened(const std::vector<Vec3>& readings,
                                    const CalibrationOptions& options);

}  // namespace accelcal::internal
