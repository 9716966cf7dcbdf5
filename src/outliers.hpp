#pragma once
// The discordant-position test of calibrate.hpp (OutlierPolicy), on one converged fit.

#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"

namespace accelcal::internal {

struct Screening {
  bool ran = false;            ///< false: too few positions or a singular fit (see note)
  std::vector<double> t;       ///< t_k per position of the fit (NaN: not tested, h_k ≈ 1)
  std::vector<double> e;       ///< normal residuals e_k [raw]
  double scatter = 0;          ///< s [raw]
  int degrees_of_freedom = 0;  ///< of t_k: m − P − 1
  double threshold = 0;        ///< |t| with two-sided probability false_alarm / m
  int most_discordant = -1;    ///< index of the largest |t_k|, −1 when none was tested
  /// Some |e_k| / (s_robust √(1 − h_k)) beyond the threshold, s_robust = 1.4826 · median of
  /// |e_j| / √(1 − h_j): a scale that a few discordant positions cannot inflate, so that two of
  /// them cannot hide each other (masking) from the t test.
  bool suspicious = false;
  std::string note;  ///< why the test could not run, or which positions it could not test

  bool significant() const {
    return most_discordant >= 0 && std::abs(t[std::size_t(most_discordant)]) > threshold;
  }
  OutlierFinding Finding(int index) const;  ///< position = index (of the fit), not excluded
};

/// The statistics of OutlierPolicy at `result` (any frame, any method with directions).
Screening ScreenPositions(const CalibrationResult& result, double false_alarm_probability);

}  // namespace accelcal::internal
