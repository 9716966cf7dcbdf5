// Binary logs read natively (native_log.hpp): the format told by the first bytes, one stream
// chosen and made a RawLog as a text log's columns are.
#include "accelcal/native_log.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/binary_stream.hpp"
#include "io/dataflash.hpp"
#include "io/mat_file.hpp"
#include "io/mcap.hpp"
#include "io/native_input.hpp"
#include "io/ros_topics.hpp"
#include "io/rosbag.hpp"
#include "io/rosbag2_sqlite.hpp"
#include "io/stream_columns.hpp"
#include "io/ulog.hpp"

namespace accelcal {

std::string_view ToString(LogFormat format) { return NameOf(format); }

LogFormat DetectLogFormat(std::string_view first_bytes) {
  if (internal::IsULog(first_bytes)) return LogFormat::kULog;
  if (internal::IsDataFlash(first_bytes)) return LogFormat::kDataFlash;
  if (internal::IsRosBag(first_bytes)) return LogFormat::kRosBag;
  if (internal::IsMcap(first_bytes)) return LogFormat::kMcap;
  if (internal::IsMatFile(first_bytes)) return LogFormat::kMat;
  if (internal::IsSqlite(first_bytes)) return LogFormat::kRosbag2Sqlite;
  return LogFormat::kText;
}

namespace {

using internal::Format;

using internal::Choose;
using internal::Chosen;
using internal::Find;
using internal::IsMicrosecondColumn;
using internal::kMicrosecondFields;
using internal::Known;
using internal::Shown;
using internal::Stored;

LogStreamInfo Describe(const internal::DecodedStream& s) {
  LogStreamInfo info;
  info.topic = s.topic;
  info.type = s.type;
  info.instance = s.instance;
  info.device_id = s.device_id;
  info.frame_id = s.frame_id;
  info.frames = s.frames;
  info.samples = s.messages;
  info.first_s = static_cast<double>(s.first_us) / 1e6;
  info.last_s = static_cast<double>(s.last_us) / 1e6;
  if (s.messages >= 2 && s.last_us > s.first_us) {
    info.rate_hz = static_cast<double>(s.messages - 1) / (info.last_s - info.first_s);
  }
  info.unreadable = s.unreadable;
  if (s.unreadable.empty()) {
    for (std::string_view sensor : KnownSensors(s.type)) info.sensors.emplace_back(sensor);
  }
  return info;
}

// "sensor_accel instance 1 (device id 2424842, 1200 samples at 200 Hz)", for lists.
std::string Line(const internal::DecodedStream& s) {
  std::string out = Shown(s.topic) + Format(" instance %d (", s.instance);
  if (s.device_id) out += Format("device id %llu, ", static_cast<unsigned long long>(*s.device_id));
  const LogStreamInfo info = Describe(s);
  out += Format("%zu samples", s.messages);
  if (info.rate_hz > 0) out += Format(" at %.4g Hz", info.rate_hz);
  return out + ")";
}

// Whether a parameter belongs to the calibration the autopilot applies to `sensor`'s readings:
// PX4's CAL_ACC*, CAL_GYRO*, SENS_BOARD_*; ArduPilot's INS_ACC*, INS_GYR*, INS_TCAL* (its
// temperature calibration, applied before the offsets), AHRS_ORIENTATION. The other sensor's own
// (an accelerometer's INS_GYROFFS, which ArduPilot learns at each boot) are not.
bool CalibrationParameter(const std::string& name, std::string_view sensor) {
  bool calibration = false;
  for (const char* prefix : {"CAL_ACC", "CAL_GYRO", "SENS_BOARD_", "INS_ACC", "INS_GYR", "INS_TCAL",
                             "AHRS_ORIENTATION"}) {
    calibration = calibration || name.rfind(prefix, 0) == 0;
  }
  const char* other = sensor == "gyroscope" ? "ACC" : "GYR";
  return calibration && name.find(other, 4) == std::string::npos;
}

// The calibration parameters in force at the first sample of `s`: each one's last value logged
// at or before it (a recalibration logged before the session wins over the values at the log's
// start), or its first value when it was first logged later (ArduPilot logs its parameters while
// the first records are written). Throws InputError naming the parameter, both values and their
// times when one changes during the samples: their calibration in force is then two.
std::map<std::string, double> CalibrationInForce(const internal::DecodedLog& log,
                                                 const internal::DecodedStream& s,
                                                 std::string_view sensor,
                                                 const std::string& source) {
  std::map<std::string, double> out;
  for (const auto& [name, history] : log.parameter_history) {
    if (history.empty() || !CalibrationParameter(name, sensor)) continue;
    std::size_t in_force = 0;
    while (in_force + 1 < history.size() && history[in_force + 1].first <= s.first_us) {
      ++in_force;
    }
    const double value = history[in_force].second;
    out[name] = value;
    for (std::size_t k = in_force + 1; k < history.size(); ++k) {
      const auto [t_us, changed] = history[k];
      if (t_us > s.first_us && t_us <= s.last_us && !(changed == value)) {
        throw InputError(
            source, 0,
            Format("the calibration parameter %s changes from %.9g (logged at %.6f s) to %.9g at "
                   "%.6f s, during the samples of %s (%.6f s to %.6f s): the %s readings were "
                   "taken under two calibrations; calibrate a log whose samples have one",
                   Shown(name).c_str(), value, static_cast<double>(history[in_force].first) / 1e6,
                   changed, static_cast<double>(t_us) / 1e6, Line(s).c_str(),
                   static_cast<double>(s.first_us) / 1e6, static_cast<double>(s.last_us) / 1e6,
                   std::string(sensor).c_str()));
      }
    }
  }
  return out;
}

}  // namespace

namespace internal {

namespace {

// The format's name for messages, with its article.
const char* FormatName(LogFormat format) {
  switch (format) {
    case LogFormat::kULog:
      return "a PX4 ULog";
    case LogFormat::kDataFlash:
      return "an ArduPilot DataFlash log";
    case LogFormat::kRosBag:
      return "a ROS bag";
    case LogFormat::kMcap:
      return "an MCAP file";
    case LogFormat::kRosbag2Sqlite:
      return "a ROS 2 bag (SQLite)";
    case LogFormat::kMat:
    case LogFormat::kText:
      break;
  }
  return "a text log";
}

// Several sensors published on one ROS topic, told apart by header.frame_id alone (MCAP and
// rosbag2 carry no publisher): the messages of the frame `options` names, else the refusal that
// lists the frames (read as one they would be one sensor at twice the rate, its bias their mean).
void ChooseFrame(internal::DecodedStream* s, const ReadOptions& options,
                 const std::string& source) {
  std::string listed;
  for (const auto& [id, messages] : s->frames) {
    listed +=
        Format("%s'%s' (%zu messages)", listed.empty() ? "" : ", ", Shown(id).c_str(), messages);
  }
  if (options.frame_id.empty()) {
    if (s->frames.size() <= 1) return;
    throw InputError(source, 0,
                     Format("%s's messages name %zu frames (header.frame_id): %s: several "
                            "sensors published on one topic, which read as one would mix their "
                            "readings; choose one with the frame option",
                            Shown(s->topic).c_str(), s->frames.size(), listed.c_str()));
  }
  if (s->frames.empty()) {
    throw InputError(source, 0,
                     Shown(s->topic) +
                         "'s messages name no frame (header.frame_id): the frame option chooses "
                         "among a ROS topic's frames");
  }
  std::size_t wanted = s->frames.size();
  for (std::size_t k = 0; k < s->frames.size(); ++k) {
    if (s->frames[k].first == options.frame_id) wanted = k;
  }
  if (wanted == s->frames.size()) {
    throw InputError(
        source, 0,
        Format("no message of %s names the frame '%s' (its frames: %s)", Shown(s->topic).c_str(),
               Shown(options.frame_id).c_str(), listed.c_str()));
  }
  if (s->frames.size() == 1) return;
  if (s->frame_of.size() != s->messages) {
    throw InputError(source, 0,
                     Shown(s->topic) +
                         ": the header.frame_id of some of its messages does not "
                         "read, so its frames cannot be told apart");
  }
  const std::size_t width = s->stored.size();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < s->messages; ++i) {
    if (s->frame_of[i] != wanted) continue;
    std::copy_n(s->values.begin() + static_cast<std::ptrdiff_t>(i * width), width,
                s->values.begin() + static_cast<std::ptrdiff_t>(kept * width));
    s->offset[kept++] = s->offset[i];
  }
  s->values.resize(kept * width);
  s->offset.resize(kept);
  s->frame_of.assign(kept, static_cast<std::uint32_t>(wanted));
  s->messages = kept;
  s->frame_id = options.frame_id;
  s->frames = {s->frames[wanted]};
}

// A binary log's format, from its first bytes in `in`.
LogFormat FormatOf(BinaryStream& in) {
  in.Need(16);
  return DetectLogFormat(std::string_view(reinterpret_cast<const char*>(in.data()),
                                          std::min<std::size_t>(in.available(), 16)));
}

DecodedLog Decode(BinaryStream& in, LogFormat format, const KeepStream& keep,
                  const StoreColumns& store, const std::string* path) {
  switch (format) {
    case LogFormat::kULog:
      return ReadULog(in, keep, store);
    case LogFormat::kDataFlash:
      return ReadDataFlash(in, keep, store);
    case LogFormat::kRosBag:
      return ReadRosBag(in, keep, store);
    case LogFormat::kMcap:
      return ReadMcap(in, keep, store);
    case LogFormat::kRosbag2Sqlite:
      // A database is opened by its path (libsqlite3), read-only and immutable.
      if (path == nullptr) {
        throw InputError(in.name(), 0,
                         "a ROS 2 bag in SQLite is read from its file (libsqlite3 opens it by its "
                         "path), not from memory or a pipe");
      }
      return ReadRosbag2Sqlite(*path, in.name(), keep, store);
    case LogFormat::kMat:
    case LogFormat::kText:
      break;
  }
  throw std::logic_error("Decode: not a log of streams");
}

// The stream: the topic's (and instance's) with messages; InputError listing the candidates
// when there is none or several (`cut`: how the log was cut short, if it was).
DecodedStream& TheStream(DecodedLog* log, const ReadOptions& options, std::string_view sensor,
                         const std::string& source, const std::string& cut) {
  std::vector<DecodedStream*> candidates;
  for (DecodedStream& s : log->streams) {
    if (!s.kept || s.messages == 0) continue;
    if (options.instance && static_cast<double>(s.instance) != *options.instance) continue;
    candidates.push_back(&s);
  }
  if (candidates.size() != 1) {
    std::string list;
    for (const DecodedStream& s : log->streams) {
      if (s.messages > 0 &&
          (options.topic.empty() ? Known(s.type, sensor) != nullptr : s.topic == options.topic)) {
        list += "; " + Line(s);
      }
    }
    const std::string what = options.topic.empty() ? std::string(sensor) + " stream"
                                                   : "stream of topic " + Shown(options.topic);
    const std::string which =
        options.instance ? Format(" with instance %g", *options.instance) : std::string();
    if (candidates.empty()) {
      std::string topics;
      for (const DecodedStream& s : log->streams) {
        if (s.messages > 0) topics += (topics.empty() ? "" : ", ") + Shown(s.topic);
      }
      throw InputError(source, 0,
                       "no " + what + which + " with samples" +
                           (list.empty() ? " (its topics: " + topics + ")" : ":" + list.substr(1)) +
                           cut);
    }
    throw InputError(source, 0,
                     "several " + what + "s:" + list.substr(1) +
                         "; choose one with the topic and instance options");
  }
  return *candidates.front();
}

// The chosen columns of `s`'s messages as samples, a FIFO's unpacked and a delta's divided by its
// interval, each checked: finite, times not going backwards, temperatures within range.
void AppendSamples(const DecodedLog& log, const DecodedStream& s, const Chosen& chosen,
                   bool microseconds, std::string_view sensor, const std::string& source,
                   RawLog* raw) {
  const std::size_t width = s.stored.size(), first = chosen.time ? 1 : 0;
  if (chosen.time) raw->time_s.reserve(s.messages);
  raw->samples.reserve(s.messages);
  raw->line.reserve(s.messages);
  // Beyond 2^53 a time in µs is no longer an exact double.
  constexpr double kExact = 9007199254740992.0;
  using Packing = KnownStream::Packing;
  if (chosen.unmeasured && s.messages > 0) {
    bool all = true;
    for (std::size_t i = 0; i < s.messages && all; ++i) all = s.values[i * width + width - 1] == -1;
    if (all) {
      // REP 145: the publisher has no such readings (an IMU without a gyroscope, say).
      const std::string& x = (*s.columns)[chosen.axis[0]];
      throw InputError(source, 0,
                       Format("%s's %s is -1 in every message, which marks (REP 145) its %s as "
                              "not measured: the topic has no %s readings",
                              Shown(s.topic).c_str(), (*s.columns)[*chosen.unmeasured].c_str(),
                              x.substr(0, x.rfind('.')).c_str(), std::string(sensor).c_str()));
    }
  }
  // The temperature's place in a stored row: before the unmeasured marker, which is last.
  const std::size_t temperature_at = width - 1 - (chosen.unmeasured ? 1 : 0);
  if (chosen.temperature) raw->temperature_c.reserve(s.messages);
  for (std::size_t i = 0; i < s.messages; ++i) {
    const double* row = s.values.data() + i * width;
    const auto where = [&] {
      return Format("%s message %zu (%s %llu)", Shown(s.topic).c_str(), i + 1,
                    log.offset_name.c_str(), static_cast<unsigned long long>(s.offset[i]));
    };
    // NaN: the driver did not measure it (PX4's default); any other value must be a sensor's.
    const double t_c = chosen.temperature ? row[temperature_at] : 0.0;
    if (chosen.temperature && !std::isnan(t_c) && !InTemperatureRange(t_c)) {
      throw InputError(
          source, 0,
          where() + Format(": its temperature (field %s) is %.9g, outside %g to %g degC",
                           (*s.columns)[*chosen.temperature].c_str(), t_c, kTemperatureRange_C[0],
                           kTemperatureRange_C[1]));
    }
    if (chosen.time && !std::isfinite(row[0])) {
      throw InputError(source, 0, where() + " holds a time that is not a finite number");
    }
    if (chosen.time && microseconds && !(std::abs(row[0]) < kExact)) {
      throw InputError(source, 0,
                       where() + Format(": its time %.17g us is beyond 2^53, where a time is "
                                        "no longer exact",
                                        row[0]));
    }
    // The message's samples: one, or a FIFO's (the last at the message's time, dt apart).
    const double* extra = row + first + 3;
    std::size_t n = 1;
    double dt_us = 0, scale = 1;
    if (chosen.packing == Packing::kFifo) {
      dt_us = extra[0], scale = extra[1];
      const double samples = extra[2];
      if (!(samples >= 1 && samples <= static_cast<double>(chosen.fifo)) ||
          samples != std::floor(samples) || !(dt_us > 0) || !std::isfinite(dt_us) ||
          !std::isfinite(scale)) {
        throw InputError(source, 0,
                         where() + Format(": a FIFO message of %g samples %g us apart (at most "
                                          "%zu, more than 0 us apart)",
                                          samples, dt_us, chosen.fifo));
      }
      n = static_cast<std::size_t>(samples);
    }
    for (std::size_t k = 0; k < n; ++k) {
      Vec3 v(row[first], row[first + 1], row[first + 2]);
      if (chosen.packing == Packing::kFifo && k > 0) {
        const std::size_t f = chosen.fifo - 1;
        v = Vec3(extra[3 + (k - 1)], extra[3 + f + (k - 1)], extra[3 + 2 * f + (k - 1)]);
      }
      if (chosen.packing == Packing::kFifo) v *= scale;
      if (chosen.packing == Packing::kDelta) {
        if (!(extra[0] > 0)) {
          throw InputError(
              source, 0,
              where() + Format(": an interval of %g us, over which the sum was taken", extra[0]));
        }
        v /= extra[0] * 1e-6;
      }
      if (!v.allFinite()) {
        throw InputError(source, 0, where() + " holds a value that is not a finite number");
      }
      if (chosen.time) {
        const double t = row[0] - static_cast<double>(n - 1 - k) * dt_us;
        if (!raw->time_s.empty() && t < raw->time_s.back()) {
          throw InputError(source, 0,
                           where() + Format(": time goes backwards (%.17g after %.17g %s)", t,
                                            raw->time_s.back(), microseconds ? "us" : "as read"));
        }
        raw->time_s.push_back(t);
      }
      raw->samples.push_back(v);
      raw->line.push_back(static_cast<std::uint32_t>(std::min<std::size_t>(i + 1, UINT32_MAX)));
      if (chosen.temperature) raw->temperature_c.push_back(t_c);
    }
  }
}

// A time in µs the same in every message: the driver does not stamp its samples; InputError
// naming another time the stream has, or the options that read one.
void RefuseUnstampedTimes(const DecodedStream& s, const Chosen& chosen, const RawLog& raw,
                          const std::string& source) {
  if (!(raw.time_s.size() >= 2 && raw.time_s.front() == raw.time_s.back() &&
        std::is_sorted(raw.time_s.begin(), raw.time_s.end()))) {
    return;
  }
  // A driver that does not stamp its samples (a ROS publisher's header.stamp, a PX4 driver's
  // timestamp_sample left 0): another time the stream has is the one there is, the time the
  // recorder logged each message (ROS's log_time, ULog's timestamp, DataFlash's TimeUS).
  const std::string& field = (*s.columns)[*chosen.time];
  std::string other;
  const auto offer = [&](const char* candidate) {
    const std::optional<std::size_t> c = Find(s, candidate);
    if (other.empty() && c && *c != *chosen.time && IsMicrosecondColumn(s, *c)) other = candidate;
  };
  offer(internal::kLogTime);
  for (const char* candidate : kMicrosecondFields) offer(candidate);
  const std::string axes = (*s.columns)[chosen.axis[0]] + "," + (*s.columns)[chosen.axis[1]] + "," +
                           (*s.columns)[chosen.axis[2]];
  throw InputError(
      source, 0,
      Format("%s's %s is the same in every message (%.17g us): the sensor's driver does not "
             "stamp them; %s",
             Shown(s.topic).c_str(), field.c_str(), raw.time_s.front(),
             other.empty()
                 ? Format("name a time that changes with the columns option (time,%s), or "
                          "give the rate option",
                          axes.c_str())
                       .c_str()
                 : Format("read the time the recorder logged each with the columns option "
                          "(%s,%s)",
                          other.c_str(), axes.c_str())
                       .c_str()));
}

}  // namespace

InputData ReadNativeLog(BinaryStream& in, InputFile* file, const ReadOptions& options,
                        const std::string* path) {
  const std::string source = in.name();
  const LogFormat format = FormatOf(in);
  const std::string name = FormatName(format);
  if (options.kind == InputKind::kPositions) {
    throw InputError(source, 0, name + " is a raw log, not a positions file");
  }
  Sha256 hash;
  if (options.fingerprint) in.Fingerprint(&hash);
  // Keep the topic asked for, or every stream of the sensor accelcal knows; store only the
  // columns the samples come from (none when they cannot be chosen: the error comes below).
  const std::string_view sensor = NameOf(options.sensor);
  const auto keep = [&](const DecodedStream& s) {
    return options.topic.empty() ? Known(s.type, sensor) != nullptr : s.topic == options.topic;
  };
  const auto store = [&](const DecodedStream& s) {
    try {
      return Stored(Choose(s, options, Known(s.type, sensor), source));
    } catch (const InputError&) {
      return std::vector<std::size_t>();
    }
  };
  // (Standard input, even redirected from a file, has no path to open.)
  if (file == nullptr || !file->regular() || (path != nullptr && *path == "-")) path = nullptr;
  DecodedLog log = Decode(in, format, keep, store, path);
  in.Drain();
  if (options.fingerprint && file != nullptr) RequireUnchanged(*file);
  const std::string cut = log.truncated ? "; " + *log.truncated : std::string();
  DecodedStream& s = TheStream(&log, options, sensor, source, cut);
  ChooseFrame(&s, options, source);
  const Chosen chosen = Choose(s, options, Known(s.type, sensor), source);
  if (s.stored != Stored(chosen)) {
    throw std::logic_error("ReadNativeLog: the columns stored are not the columns chosen");
  }
  // A time field the format defines is in µs; another the user chose is read as a text log's.
  const bool microseconds = chosen.time && IsMicrosecondColumn(s, *chosen.time);
  if (microseconds && options.time_unit != TimeUnit::kAuto &&
      options.time_unit != TimeUnit::kMicroseconds) {
    throw InputError(
        source, 0,
        name + "'s " + (*s.columns)[*chosen.time] +
            (format == LogFormat::kRosBag || format == LogFormat::kMcap ||
                     format == LogFormat::kRosbag2Sqlite
                 ? " is a ROS time (seconds and nanoseconds) by its specification: "
                   "the time unit option (" +
                       std::string(ToString(options.time_unit)) + ") does not apply to it"
                 : " is in microseconds by its specification, not in " +
                       std::string(ToString(options.time_unit))));
  }
  InputData data;
  data.kind = InputKind::kRaw;
  data.kind_reason = name + ": " + Line(s);
  if (const KnownStream* known = Known(s.type, sensor); known != nullptr && known->corrected) {
    data.kind_reason +=
        ", already corrected by the calibration in force when it was logged: what is calibrated "
        "is what that calibration left";
  }
  RawLog& raw = data.raw;
  raw.source = source;
  AppendSamples(log, s, chosen, microseconds, sensor, source, &raw);
  if (log.truncated) raw.read_warning = *log.truncated;
  if (std::all_of(raw.temperature_c.begin(), raw.temperature_c.end(),
                  [](double t) { return std::isnan(t); })) {
    if (chosen.temperature && !options.temperature.empty() && !raw.temperature_c.empty()) {
      throw InputError(source, 0,
                       Shown(s.topic) + "'s " + (*s.columns)[*chosen.temperature] +
                           ", the temperature asked for, is NaN (not measured) in every message");
    }
    raw.temperature_c.clear();  // a driver that measures none
  } else {
    raw.temperature_source = s.topic + "." + (*s.columns)[*chosen.temperature];
  }
  SourceStream& stream = data.stream.emplace();
  stream.format = std::string(ToString(format));
  stream.topic = s.topic;
  stream.type = s.type;
  stream.instance = s.instance;
  stream.device_id = s.device_id;
  const KnownStream* known = Known(s.type, sensor);
  stream.corrected = known != nullptr && known->corrected;
  // The unit of a known stream's readings, when they are what was read (by default, or named).
  if (known != nullptr &&
      (chosen.packing != KnownStream::Packing::kSample ||
       ((*s.columns)[chosen.axis[0]] == known->x && (*s.columns)[chosen.axis[1]] == known->y &&
        (*s.columns)[chosen.axis[2]] == known->z))) {
    stream.unit = std::string(known->unit);
  }
  stream.calibration_in_force = CalibrationInForce(log, s, sensor, source);
  if (microseconds) RefuseUnstampedTimes(s, chosen, raw, source);
  try {
    FinishRawLog(&raw, microseconds ? TimeUnit::kMicroseconds : options.time_unit, options.rate_hz,
                 chosen.time ? std::string_view((*s.columns)[*chosen.time]) : std::string_view());
  } catch (const InputError& e) {
    // A sample's error (a recording that repeats each sample): its line is its message's number,
    // named as the errors above name a message, by its topic, number and byte.
    if (e.line() == 0 || e.line() > s.offset.size()) throw;
    throw InputError(
        source, 0,
        Format("%s message %zu (%s %llu): ", Shown(s.topic).c_str(), e.line(),
               log.offset_name.c_str(), static_cast<unsigned long long>(s.offset[e.line() - 1])) +
            e.reason());
  }
  if (options.fingerprint) {
    data.bytes = in.offset();
    data.sha256 = hash.HexDigest();
  }
  return data;
}

}  // namespace internal

LogInventory InspectLog(const std::string& path) {
  internal::InputFile file(path, ReadOptions{}.max_stream_bytes);
  std::string head(16, '\0');
  head.resize(file.ReadFully(head.data(), head.size()));
  LogInventory out;
  out.format = DetectLogFormat(head);
  out.source = file.name();
  if (out.format == LogFormat::kText) {
    throw InputError(
        file.name(), 0,
        "not a binary log (PX4 ULog, ArduPilot DataFlash, ROS bag, MCAP, ROS 2 SQLite bag, "
        "MAT-file): a text "
        "log's "
        "columns are its header's");
  }
  if (out.format == LogFormat::kMat) {
    // Its variables, as streams: a matrix's rows are its samples.
    if (!file.regular() || path == "-") {
      throw InputError(file.name(), 0,
                       "a MAT-file is read from its file, not from standard input or a pipe");
    }
    for (const internal::MatVariable& v : internal::ListMatVariables(path)) {
      LogStreamInfo info;
      info.topic = v.name;
      for (std::size_t d : v.dims) info.type += (info.type.empty() ? "" : "x") + std::to_string(d);
      info.type += " " + v.type;
      if (v.numeric_matrix) {
        const bool turned = v.dims[1] > 16 && v.dims[0] <= 16;  // as ReadMatTable reads it
        info.samples = turned ? v.dims[1] : v.dims[0];
        if (turned) info.type += ", its samples as columns: read turned";
      }
      if (v.name.empty()) {  // as ReadMatTable refuses it
        info.unreadable =
            "it has no name (its name element is empty or not text): a variable is read by its "
            "name";
      }
      out.streams.push_back(std::move(info));
    }
    out.bytes = file.size();
    return out;
  }
  internal::BinaryStream in(&file, std::move(head));
  const internal::DecodedLog log = internal::Decode(
      in, out.format, [](const internal::DecodedStream&) { return false; }, {},
      file.regular() && path != "-" ? &path : nullptr);
  // A database is read by SQLite, not through the stream: its size is the file's.
  out.bytes = out.format == LogFormat::kRosbag2Sqlite ? file.size() : log.bytes;
  for (const internal::DecodedStream& s : log.streams) {
    out.streams.push_back(Describe(s));
    out.fields.emplace(s.topic, *s.columns);  // the first subscription's: a topic has one format
  }
  out.parameters = log.parameters;
  for (const auto& [name, history] : log.parameter_history) {
    for (std::size_t k = 1; k < history.size(); ++k) {
      if (!(history[k].second == history[k - 1].second)) {
        out.parameter_changes.push_back(
            {name, static_cast<double>(history[k].first) / 1e6, history[k].second});
      }
    }
  }
  std::stable_sort(out.parameter_changes.begin(), out.parameter_changes.end(),
                   [](const LogInventory::ParameterChange& a,
                      const LogInventory::ParameterChange& b) { return a.time_s < b.time_s; });
  out.info = log.info;
  out.truncated = log.truncated;
  return out;
}

}  // namespace accelcal
