#pragma once
// A decoded stream's columns (stream_columns.cpp): the streams accelcal knows by their type and
// which of their fields are a sensor's readings, or the fields the columns option names.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/log_reader.hpp"
#include "accelcal/native_log.hpp"
#include "io/decoded_log.hpp"

namespace accelcal::internal {

/// The known stream of `type` (ROS 1 or 2 spelling) for `sensor`, or null.
const KnownStream* Known(std::string_view type, std::string_view sensor);

// A name from the log, for a message: one line, every character visible.
std::string Shown(std::string_view name);

// The fields of `s`, escaped, for a message that lists them.
std::string Fields(const DecodedStream& s);

// The index of the column `name` of `s`, if it has one.
std::optional<std::size_t> Find(const DecodedStream& s, std::string_view name);

// The time fields the formats define in µs by name (ULog's timestamp and timestamp_sample,
// DataFlash's TimeUS and SampleUS), in the order they are preferred when none is named. A ROS
// message's are known by their type (DecodedStream::microseconds): header.stamp is preferred,
// then log_time.
inline constexpr const char* kMicrosecondFields[] = {"timestamp_sample", "timestamp", "SampleUS",
                                                     "TimeUS"};

// Whether column `c` of `s` is a time its format or reader gives in µs.
bool IsMicrosecondColumn(const DecodedStream& s, std::size_t c);

// The columns a stream's samples come from: its time (if any) and x, y, z.
struct Chosen {
  std::optional<std::size_t> time;
  std::size_t axis[3];
  KnownStream::Packing packing = KnownStream::Packing::kSample;
  // kDelta: the interval's column. kFifo: dt, scale, samples, then x[1..], y[1..], z[1..] (x[0],
  // y[0], z[0] being the axes): `fifo` samples a message at most.
  std::vector<std::size_t> extra;
  std::size_t fifo = 1;
  std::optional<std::size_t> temperature;  // ReadOptions::temperature's, or the known stream's
  std::optional<std::size_t> unmeasured;   // KnownStream::unmeasured's column, stored last
};

// The columns option's (time,x,y,z, or x,y,z with the stream's own time field when it has one),
// else the known stream's. Throws InputError naming what is wrong.
Chosen Choose(const DecodedStream& s, const ReadOptions& options, const KnownStream* known,
              const std::string& source);

// The stored order of a Chosen: time first when there is one.
std::vector<std::size_t> Stored(const Chosen& c);

}  // namespace accelcal::internal
