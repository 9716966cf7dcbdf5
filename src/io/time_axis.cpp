#include "accelcal/time_axis.hpp"

#include <algorithm>
#include <cmath>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"

namespace accelcal {

using internal::Format;

std::string_view ToString(TimeUnit unit) { return NameOf(unit); }

std::optional<TimeUnit> TimeUnitFromString(std::string_view text) {
  return FromName<TimeUnit>(text);
}

double UnitsPerSecond(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::kAuto:
      return 0;
    case TimeUnit::kSeconds:
      return 1;
    case TimeUnit::kMilliseconds:
      return 1e3;
    case TimeUnit::kMicroseconds:
      return 1e6;
    case TimeUnit::kNanoseconds:
      break;
  }
  return 1e9;
}

double SecondsPer(TimeUnit unit) {
  // 1 / 1e3 is the double nearest 1e-3 (a division is correctly rounded): the same constants.
  return unit == TimeUnit::kAuto ? 0 : 1 / UnitsPerSecond(unit);
}

std::vector<std::size_t> SegmentStarts(const std::vector<TimeGap>& gaps) {
  std::vector<std::size_t> starts{0};
  for (const TimeGap& g : gaps) starts.push_back(g.index);
  return starts;
}

namespace {

constexpr TimeUnit kUnits[] = {TimeUnit::kSeconds, TimeUnit::kMilliseconds, TimeUnit::kMicroseconds,
                               TimeUnit::kNanoseconds};

const char* UnitWord(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::kSeconds:
      return "seconds";
    case TimeUnit::kMilliseconds:
      return "milliseconds";
    case TimeUnit::kMicroseconds:
      return "microseconds";
    default:
      return "nanoseconds";
  }
}

bool EndsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

struct NameHint {
  std::optional<TimeUnit> unit;
  bool explicit_unit = false;  // the name states the unit (else it only suggests one)
};

// What a (lower-case) time column name says of its unit.
NameHint HintOf(std::string_view name) {
  if (name.empty()) return {};
  // "t[us]", "time(ms)": a unit in brackets.
  const std::size_t open = name.find_first_of("[(");
  if (open != std::string_view::npos && open > 0 && name.size() > open + 2 &&
      (name.back() == ']' || name.back() == ')')) {
    const std::string_view unit = name.substr(open + 1, name.size() - open - 2);
    for (TimeUnit u : kUnits) {
      if (unit == ToString(u) || (u == TimeUnit::kMicroseconds && unit == "µs")) {
        return {u, true};
      }
    }
  }
  // rostopic echo -p writes "%time" in ns; ROS header stamps are ns as well.
  if (name == "%time" || EndsWith(name, "stamp_ns") || EndsWith(name, "header.stamp")) {
    return {TimeUnit::kNanoseconds, true};
  }
  if (name == "timeus") return {TimeUnit::kMicroseconds, true};  // ArduPilot's TimeUS
  if (name == "timems") return {TimeUnit::kMilliseconds, true};
  if (name == "time" || name == "t") return {TimeUnit::kSeconds, false};
  if (name == "timestamp" || name == "timestamp_sample") {  // PX4 ulog2csv: µs
    return {TimeUnit::kMicroseconds, false};
  }
  struct Suffix {
    const char* text;
    TimeUnit unit;
  };
  static const Suffix kSuffixes[] = {
      {"_ns", TimeUnit::kNanoseconds},  {"_nsec", TimeUnit::kNanoseconds},
      {"_us", TimeUnit::kMicroseconds}, {"_usec", TimeUnit::kMicroseconds},
      {"_ms", TimeUnit::kMilliseconds}, {"_msec", TimeUnit::kMilliseconds},
      {"_s", TimeUnit::kSeconds},       {"_sec", TimeUnit::kSeconds},
      {"_seconds", TimeUnit::kSeconds},
  };
  for (const Suffix& s : kSuffixes) {
    if (EndsWith(name, s.text)) return {s.unit, true};
  }
  return {};
}

bool Plausible(double rate_hz) {
  return rate_hz >= kMinPlausibleRate_hz && rate_hz <= kMaxPlausibleRate_hz;
}

std::string RateText(double rate_hz) {
  return rate_hz >= 1000 ? Format("%.4g kHz", rate_hz / 1000) : Format("%.4g Hz", rate_hz);
}

// The median of (t[i+B] − t[i]) / B over non-overlapping blocks of B steps.
double TypicalStep(const std::vector<double>& t) {
  const std::size_t steps = t.size() - 1;
  const std::size_t block = std::max<std::size_t>(1, std::min<std::size_t>(16, steps / 4));
  std::vector<double> per_block;
  per_block.reserve(steps / block);
  for (std::size_t i = 0; i + block < t.size(); i += block) {
    per_block.push_back((t[i + block] - t[i]) / static_cast<double>(block));
  }
  const auto mid = per_block.begin() + static_cast<std::ptrdiff_t>(per_block.size() / 2);
  std::nth_element(per_block.begin(), mid, per_block.end());
  return *mid;
}

}  // namespace

TimeAxis MakeTimeAxis(std::vector<double>* time, TimeUnit unit, std::string_view column_name) {
  std::vector<double>& t = *time;
  if (t.size() < 2) throw DataError("the time column needs at least two samples");
  const double step = TypicalStep(t);
  if (!(step > 0)) {
    const double span = t.back() - t.front();
    if (!(span > 0)) throw DataError("the timestamps do not advance");
    throw DataError(Format(
        "the timestamps advance in fewer than half of the blocks of samples (median step 0 over "
        "a span of %.9g): repeated timestamps, not a sample clock",
        span));
  }
  TimeAxis axis;
  const std::string column = column_name.empty() ? std::string("the time column")
                                                 : "time column '" + std::string(column_name) + "'";
  const auto rate_in = [&](TimeUnit u) { return 1.0 / (step * SecondsPer(u)); };
  if (unit != TimeUnit::kAuto) {
    if (!(rate_in(unit) >= kMinLogRate_hz && rate_in(unit) <= kMaxLogRate_hz)) {
      throw DataError(
          Format("%s in %s, as given, has a median step of %.6g: %s, outside the "
                 "%g Hz-%g MHz of any log (another unit?)",
                 column.c_str(), UnitWord(unit), step, RateText(rate_in(unit)).c_str(),
                 kMinLogRate_hz, kMaxLogRate_hz / 1e6));
    }
    axis.unit = unit;
    axis.unit_reason = Format("given: %s", UnitWord(unit));
  } else {
    const NameHint hint = HintOf(column_name);
    if (hint.unit && Plausible(rate_in(*hint.unit))) {
      axis.unit = *hint.unit;
      axis.unit_reason =
          Format("%s read as %s (%s by its name; median step %.6g: %s)", column.c_str(),
                 UnitWord(*hint.unit), hint.explicit_unit ? "stated" : "suggested", step,
                 RateText(rate_in(*hint.unit)).c_str());
    } else if (hint.unit && hint.explicit_unit) {
      throw DataError(Format(
          "%s is in %s by its name, but its median step %.6g would then be %s, outside the "
          "%g Hz-%g kHz of an IMU log: the column is not what its name says (give the time unit)",
          column.c_str(), UnitWord(*hint.unit), step, RateText(rate_in(*hint.unit)).c_str(),
          kMinPlausibleRate_hz, kMaxPlausibleRate_hz / 1000));
    } else {
      std::vector<TimeUnit> candidates;
      for (TimeUnit u : kUnits) {
        if (Plausible(rate_in(u))) candidates.push_back(u);
      }
      if (candidates.size() != 1) {
        std::string readings;
        for (TimeUnit u : kUnits) {
          if (!readings.empty()) readings += ", ";
          readings += Format("%s in %s", RateText(rate_in(u)).c_str(), UnitWord(u));
        }
        throw DataError(Format(
            "cannot tell the unit of %s: its median step %.6g is %s; %s (give the time unit: "
            "s, ms, us or ns)",
            column.c_str(), step, readings.c_str(),
            candidates.empty() ? "none is an IMU rate (2 Hz-20 kHz)"
                               : "more than one is an IMU rate (2 Hz-20 kHz)"));
      }
      axis.unit = candidates.front();
      axis.unit_reason = Format("%s read as %s (its median step %.6g: %s)", column.c_str(),
                                UnitWord(axis.unit), step, RateText(rate_in(axis.unit)).c_str());
    }
  }
  // Divided by the unit's count per second (UnitsPerSecond: exact).
  const double per_second = UnitsPerSecond(axis.unit);
  axis.origin_s = t.front() / per_second;
  axis.typical_step_s = step / per_second;
  // Seconds from the first sample; the subtraction first, exact for nearby large values.
  const double t0 = t.front();
  for (double& v : t) v = (v - t0) / per_second;

  double resolution = INFINITY, spans = 0, counted = 0;
  std::size_t irregular = 0, repeated = 0, segment_begin = 0;
  const auto close_segment = [&](std::size_t end) {
    if (end - segment_begin >= 2) {
      spans += t[end - 1] - t[segment_begin];
      counted += static_cast<double>(end - segment_begin - 1);
    }
  };
  // Locals: a gap's push_back could otherwise change axis.typical_step_s for the compiler.
  const double typical = axis.typical_step_s, tolerance = 0.5 * typical, gap = kGapFactor * typical;
  // The steps up to each gap in a loop of their own, its tallies in registers (a gap's
  // push_back, inside the loop, had kept them in memory: 35 instructions a step).
  const double* const time_s = t.data();
  const std::size_t size = t.size();
  for (std::size_t i = 1; i < size;) {
    double least = resolution;
    std::size_t repeats = 0, irregulars = 0, j = i;
    for (; j < size; ++j) {
      const double d = time_s[j] - time_s[j - 1];
      if (d > 0) least = std::min(least, d);
      repeats += d == 0;
      irregulars += std::abs(d - typical) > tolerance;
      if (d > gap) break;
    }
    resolution = least;
    repeated += repeats;
    irregular += irregulars;
    if (j < size) {  // a gap before sample j
      close_segment(j);
      axis.gaps.push_back({j, time_s[j - 1], time_s[j]});
      segment_begin = j;
      ++j;
    }
    i = j;
  }
  close_segment(t.size());
  axis.resolution_s = std::isfinite(resolution) ? resolution : 0;
  if (!(spans > 0)) throw DataError("the timestamps do not advance within any segment");
  axis.rate_hz = counted / spans;
  const double steps = static_cast<double>(t.size() - 1);
  axis.repeated_fraction = static_cast<double>(repeated) / steps;
  axis.irregular_fraction =
      axis.repeated_fraction > 0.05 ? 0.0 : static_cast<double>(irregular) / steps;
  return axis;
}

}  // namespace accelcal
