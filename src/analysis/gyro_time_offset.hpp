#pragma once
// The lag of the gyroscope's readings behind the accelerometer's, from the turns: while the
// sensor tilts, the accelerometer's direction turns at the gyro's rate perpendicular to gravity,
// |ḟ| / |f| = |ω × f̂|; the shift of the gyro's stream that best aligns the two (their
// cross-correlation's peak over the turns, to a fraction of a sample by a quadratic through the
// five values around it) is the lag, and its standard error the jackknife's over the turns.
#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "accelcal/gyro_calibration.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/model.hpp"

namespace accelcal::internal {

/// The turns' samples: [first, last] inclusive, as GyroRotation's; `t` the times integrated at,
/// `step_s` their typical step. The lag is searched within ±kGyroLagSearch_s (and ± the
/// shortest turn); nullopt with fewer than 3 turns or no step. GyroTimeOffset::at_limit when the
/// peak lies on the search range's edge (the lag is larger, or the streams do not correlate).
std::optional<GyroTimeOffset> EstimateGyroLag(
    const RawLog& accel, const RawLog& gyro, const std::vector<double>& t, double step_s,
    const std::vector<std::pair<std::size_t, std::size_t>>& turns,
    const ModelParameters& accel_params, const GyroParameters& gyro_params);

inline constexpr double kGyroLagSearch_s = 0.5;

}  // namespace accelcal::internal
