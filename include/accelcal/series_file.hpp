#pragma once
/// @file series_file.hpp
/// Files of system-level samples (system_level.hpp): time [s] from platform angle 0, measured
/// platform-frame specific force [m/s²] and roll and pitch errors [rad], one sample per row.
///
/// Two layouts, told apart by the first bytes:
///   - binary: the line "accelcal-series 1 t,fx,fy,fz,roll,pitch float64le\n", then six
///     little-endian IEEE-754 doubles per sample (48 bytes): a day at 100 Hz is 415 MB and reads
///     in a fraction of a second;
///   - text: delimited rows t,fx,fy,fz,roll,pitch (commas, tabs or spaces; `#` comments; an
///     optional header line), for series exported from other tools.

#include <functional>
#include <string>
#include <string_view>

#include "accelcal/types.hpp"

namespace accelcal {

/// One sample of the system-level series: time from S = 0 [s], measured platform-frame specific
/// force [m/s²], roll and pitch errors [rad].
struct SystemSample {
  double t = 0;
  Vec3 f = Vec3::Zero();
  double roll = 0, pitch = 0;
};

/// The binary layout's first line.
inline constexpr std::string_view kSeriesMagic =
    "accelcal-series 1 t,fx,fy,fz,roll,pitch float64le\n";

/// Appends the binary header / one sample to `out`.
void AppendSeriesHeader(std::string* out);
void AppendSeriesSample(const SystemSample& sample, std::string* out);

/// Reports how far a read has come: bytes consumed of the total (for a progress bar), every
/// 65536 samples.
using SeriesProgress = std::function<void(std::size_t bytes_done, std::size_t bytes_total)>;

/// Calls `sink` with every sample of `content` in file order. Throws InputError (source, line or
/// 0 for binary, reason) for a truncated binary file, a text row without six finite numbers, or
/// no samples.
void ParseSeries(std::string_view content, const std::string& source,
                 const std::function<void(const SystemSample&)>& sink,
                 const SeriesProgress& progress = nullptr);
/// A series that is not a regular file (a pipe, standard input) is refused beyond this size.
inline constexpr std::size_t kMaxSeriesStreamBytes = std::size_t{4} << 30;
/// ParseSeries of a file, read in blocks ("-": standard input): a regular file up to the size it
/// had when opened (one that shrinks meanwhile is an InputError), anything else up to
/// kMaxSeriesStreamBytes.
void ReadSeries(const std::string& path, const std::function<void(const SystemSample&)>& sink,
                const SeriesProgress& progress = nullptr);

}  // namespace accelcal
