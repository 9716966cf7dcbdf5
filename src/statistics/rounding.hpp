#pragma once
// What rounding to a step leaves in a mean of readings, however many are averaged.
#include <cmath>

namespace accelcal::internal {

/// The variance [raw²] that the mean of readings rounded to `step` keeps whatever their number,
/// given the variance of one reading as read (`reading_variance`, rounding included). Readings
/// whose noise is well below the step do not dither: they round the same way every time, so
/// their mean is off the true value by up to half a step, uniformly over where the value falls
/// between steps (q²/12), and averaging does not take it down. Noise of σ before rounding
/// dithers it away as the rounding error's first harmonic fades, by exp(−2π²σ²/q²) in amplitude
/// (Widrow & Kollár, Quantization Noise, 2008, ch. 4-5): the floor is q²/12 · exp(−4π²σ²/q²),
/// σ² = max(0, reading_variance − q²/12). At σ = q/2 it is 5·10⁻⁵ q²/12; at σ = q/10 two thirds
/// of q²/12. 0 for a step of 0 (readings not rounded, or too finely to tell).
inline double RoundingFloorVariance(double step, double reading_variance) {
  if (!(step > 0) || !std::isfinite(step)) return 0.0;
  const double q2 = step * step;
  const double sigma2 = std::isfinite(reading_variance) && reading_variance > q2 / 12.0
                            ? reading_variance - q2 / 12.0
                            : 0.0;
  constexpr double kFourPiSquared = 39.47841760435743;
  return q2 / 12.0 * std::exp(-kFourPiSquared * sigma2 / q2);
}

}  // namespace accelcal::internal
