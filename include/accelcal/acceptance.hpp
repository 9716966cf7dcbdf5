#pragma once
/// @file acceptance.hpp
/// A production line's verdict on a calibration: the calibration's named quantities (every
/// parameter with its 1σ, the engineering quantities, the held-out error, the positions used),
/// limits on them read from a YAML file (docs/batch.md), and whether a calibration meets them.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/gravity.hpp"

namespace accelcal {

/// One quantity of a calibration, named as a limits file and batch's summary name it.
struct CalibrationQuantity {
  std::string name;  ///< e.g. "accelerometer.K_xx", "gyroscope.heldout_rms_deg"
  double value = 0;
  std::optional<double> sigma;  ///< its 1σ, when the file has the covariance it comes from
  std::string unit;             ///< e.g. "counts per m/s2", "rad", "m/s2"; "" for a count
  bool fixed = false;  ///< set by the model, not estimated (k2 = 0 in the linear model): no σ
};

/// Every quantity of `cal`, in a fixed order: the accelerometer's parameters (the file's
/// parameter_order), its engineering quantities (engineering.hpp: scale_factor_*,
/// misalignment's angles, bias_specific_force_*, k2_g_per_g2_*), rms_after, heldout_rms,
/// noise_sigma_raw, positions (used) and excluded_positions; then the gyroscope's parameters
/// (Kg_*, bg_*, G_*), scale_factor_*, rms_deg and heldout_rms_deg. Each name is prefixed by its
/// sensor ("accelerometer." or "gyroscope."); a statistic the file does not record is left out.
std::vector<CalibrationQuantity> CalibrationQuantities(const LoadedCalibration& cal);

/// Every name CalibrationQuantities can give (any model, frame and gyroscope), with whether it
/// can have a 1σ: what a limit's pattern is checked against.
struct QuantityName {
  std::string name;
  bool has_sigma = false;
};
const std::vector<QuantityName>& KnownQuantityNames();

/// `name` matched by `pattern`, where '*' stands for any run of characters (none included).
bool QuantityMatches(std::string_view pattern, std::string_view name);

/// What a limit bounds: the quantity's value or its 1σ.
enum class LimitStatistic { kValue, kSigma };

/// Bounds on the quantities a pattern names: min ≤ x ≤ max and |x| ≤ abs_max, each optional (at
/// least one given).
struct Limit {
  std::string pattern;  ///< as in the file, without ".sigma"
  LimitStatistic statistic = LimitStatistic::kValue;
  std::optional<double> min, max, abs_max;
  std::size_t line = 0;  ///< in the limits file
};

/// A limits file, read (ParseLimits).
struct AcceptanceLimits {
  std::string source;  ///< the file's name
  std::string part;    ///< `part`: what the limits are for (free text), when given
  std::vector<Limit> limits;
  /// `diagnosis.max_severity`: a finding of the calibration's diagnosis more severe than this
  /// fails it; none: findings do not (a calibration whose verdict is "failed" always fails).
  std::optional<Severity> max_severity;
  /// `units`: the specific-force unit the limits are written in, which every calibration must
  /// have (a bias bounded in m/s2 is never compared in g), and the raw unit's label, when given.
  ForceUnit specific_force_unit = ForceUnit::kMetersPerSecond2;
  std::string raw_unit;  ///< empty: any
};

/// Reads a limits file's text (YAML; its schema in docs/batch.md). Throws InputError naming
/// `source` and the line for a syntax error, an unknown key, a pattern that names no quantity, a
/// bound that is not a finite number, min above max, a negative abs_max, or a file with nothing
/// to check.
AcceptanceLimits ParseLimits(std::string_view text, const std::string& source);

/// One limit a calibration does not meet.
struct LimitFailure {
  std::string quantity;  ///< the quantity's name, with ".sigma" for its 1σ; "diagnosis", "units"
  std::optional<double> value;  ///< none: the calibration does not have it
  std::string text;             ///< e.g. "accelerometer.b_x = 1.25 is above max 1"
  std::size_t line = 0;         ///< the limit's line in the limits file (0: not a limit's)
};

/// The verdict on one calibration.
struct Acceptance {
  bool passed = true;
  /// The failed limits, in the file's order; then the diagnosis's findings above
  /// max_severity, then a "failed" verdict of the calibration's own checks.
  std::vector<LimitFailure> failures;
  std::size_t checked = 0;  ///< comparisons made (a pattern may name several quantities)
};

/// Checks `cal` against `limits`. A limit whose pattern names none of the calibration's
/// quantities (a gyroscope bound, a calibration without one; a σ the file does not have) fails:
/// what cannot be checked is not passed.
Acceptance Accept(const LoadedCalibration& cal, const AcceptanceLimits& limits);

}  // namespace accelcal
