#pragma once
// The gyroscope's offsets over temperature (GyroCalibrationOptions::thermal): each sample's
// temperature, and the polynomial fitted to the still positions' mean rates.
#include <vector>

#include "accelcal/gyro_calibration.hpp"
#include "accelcal/log_reader.hpp"
#include "solvers/gyro_fit.hpp"

namespace accelcal::internal {

/// b_g(T) fitted to `stills` (mean rates, their σ, their specific force) at `temperatures_c` (one
/// per still) by weighted least squares, per axis, beside a constant bias and, with
/// `g_sensitivity`, the three G terms of the axis. The degree is options.degree or, without one,
/// chosen from 0 up: a degree is raised while the paired held-out improvement of the whitened
/// still means (leave one position out) passes t_{n−1}(1 − kHeldOutImprovementAlpha) standard
/// errors and the added coefficients pass a Wald test at kThermalAlpha. Throws DataError when the
/// given degree is not determined (too few positions, too few distinct temperatures, a span under
/// 1 K).
GyroThermal FitGyroThermal(const std::vector<GyroStill>& stills,
                           const std::vector<double>& temperatures_c,
                           const GyroThermalOptions& options, bool g_sensitivity);

}  // namespace accelcal::internal
