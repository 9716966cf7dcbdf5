#pragma once
/// @file time_axis.hpp
/// The time column of a raw log: its unit, its rate, its gaps.
///
/// Logs converted from flight controllers and robots carry time in µs (PX4 `timestamp`,
/// ArduPilot `TimeUS`), ns (ROS `%time`, `*_ns`) or ms; read as seconds, a 100 Hz log becomes
/// 1e-4 Hz and every still period falls apart. So the unit is decided, not assumed:
///   1. a column name that states its unit (`time_ms`, `timestamp_us`, `TimeUS`, `%time`,
///      `time_ns`, `t_s`, ...) settles it, provided the median step then gives a rate in the
///      plausible band [kMinPlausibleRate_hz, kMaxPlausibleRate_hz]; otherwise the column
///      contradicts its name and the log is refused;
///   2. a name that only suggests a unit (`t` and `time`: seconds; PX4's `timestamp`: µs) is
///      followed when that unit gives a plausible rate;
///   3. otherwise the median step decides when exactly one unit gives a plausible rate. The
///      band is four decades wide and the units three apart, so a step of 0.05-0.5 reads as 2-20
///      Hz in seconds or 2-20 kHz in ms: such a log is refused with both readings.
/// The rate is taken per segment (samples minus one over the span), never over the whole log:
/// a step more than kGapFactor times the typical one is a gap (a logger pause, two sessions
/// joined) that splits the log into segments which no detection window or interval crosses.
/// The typical step is the median over blocks of 16 steps, so that timestamps printed more
/// coarsely than the sample period (the T265's 10 ms at 200 Hz: half the steps are 0) still give
/// the right step.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/names.hpp"

namespace accelcal {

enum class TimeUnit {
  kAuto,          ///< "auto": from the column's name and its median step (see above)
  kSeconds,       ///< "s"
  kMilliseconds,  ///< "ms"
  kMicroseconds,  ///< "us"
  kNanoseconds,   ///< "ns"
};
std::string_view ToString(TimeUnit unit);
std::optional<TimeUnit> TimeUnitFromString(std::string_view text);
template <>
struct EnumNames<TimeUnit> {
  static constexpr std::pair<TimeUnit, std::string_view> kTable[] = {
      {TimeUnit::kAuto, "auto"},
      {TimeUnit::kSeconds, "s"},
      {TimeUnit::kMilliseconds, "ms"},
      {TimeUnit::kMicroseconds, "us"},
      {TimeUnit::kNanoseconds, "ns"}};
};
/// Seconds per unit (1, 1e-3, 1e-6, 1e-9); kAuto has none (0).
double SecondsPer(TimeUnit unit);
/// Units per second, exactly (1, 1e3, 1e6, 1e9; kAuto 0): a time in seconds is the time in the
/// unit divided by it, the double nearest what the same time written in seconds reads as
/// (64180000 us: 64.18 s; times 1e-6 gave 64.17999999999999).
double UnitsPerSecond(TimeUnit unit);

/// A rate an IMU log can plausibly have [Hz]: 2 Hz (a window of 0.5 s holds one sample below
/// that) to 20 kHz (beyond the output rate of common MEMS accelerometers).
inline constexpr double kMinPlausibleRate_hz = 2.0;
inline constexpr double kMaxPlausibleRate_hz = 20000.0;
/// Any rate a log may be said to have [Hz] (a given time unit, a given rate): 1 mHz (a sample
/// every 17 minutes) to 1 MHz; beyond them a value is a slip of unit, never a log.
inline constexpr double kMinLogRate_hz = 1e-3;
inline constexpr double kMaxLogRate_hz = 1e6;
/// A step longer than this many typical steps is a gap.
inline constexpr double kGapFactor = 10.0;

/// A pause in the time column: the samples before `index` and from `index` on belong to
/// different segments.
struct TimeGap {
  std::size_t index = 0;  ///< first sample after the gap
  double t_before_s = 0;  ///< time of the sample before the gap [s from the first sample]
  double t_after_s = 0;   ///< time of the sample `index` [s from the first sample]
};

/// What the time column was found to be.
struct TimeAxis {
  TimeUnit unit = TimeUnit::kSeconds;  ///< never kAuto
  std::string unit_reason;             ///< why this unit ("given", or the name and step)
  /// The first timestamp in seconds (as written: an epoch time stays one). RawLog::time_s holds
  /// seconds from it.
  double origin_s = 0;
  double typical_step_s = 0;  ///< median over blocks of 16 steps [s]
  double rate_hz = 0;         ///< Σ (samples − 1) / Σ span over the segments
  std::vector<TimeGap> gaps;
  /// Smallest positive step [s]: the resolution of the timestamps when they are coarser than
  /// the sample period.
  double resolution_s = 0;
  /// Fraction of steps that are 0: timestamps written more coarsely than the samples come.
  double repeated_fraction = 0;
  /// Fraction of steps that differ from the typical step by more than half of it (0 when more
  /// than 5 % of the steps are 0: coarse timestamps say nothing of the sampling then).
  double irregular_fraction = 0;
};

/// Decides the unit of `time` (values as read, non-decreasing, at least 2), converts it in place
/// to seconds from the first sample and describes it. `column_name` is the header's name of the
/// time column, lower-case ("" when the file has no header). Throws DataError when the unit
/// cannot be settled, the name contradicts the step, or the timestamps do not advance.
TimeAxis MakeTimeAxis(std::vector<double>* time, TimeUnit unit, std::string_view column_name);

/// The first sample of every segment (0 first), from the gaps of a log of `samples` samples.
std::vector<std::size_t> SegmentStarts(const std::vector<TimeGap>& gaps);

}  // namespace accelcal
