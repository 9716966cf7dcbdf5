// Binary logs read natively (native_log.hpp): the format told by the first bytes, one stream
// chosen and made a RawLog as a text log's columns are.
#include "accelcal/native_log.hpp"

#include <algorithm>
#include <cmath>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/binary_stream.hpp"
#include "io/dataflash.hpp"
#include "io/native_input.hpp"
#include "io/ulog.hpp"

namespace accelcal {

std::string_view ToString(LogFormat format) { return NameOf(format); }

LogFormat DetectLogFormat(std::string_view first_bytes) {
  if (internal::IsULog(first_bytes)) return LogFormat::kULog;
  if (internal::IsDataFlash(first_bytes)) return LogFormat::kDataFlash;
  return LogFormat::kText;
}

const std::vector<KnownStream>& KnownStreams() {
  static const std::vector<KnownStream> kStreams = {
      // PX4: sampled at timestamp_sample where the topic has one.
      {"sensor_accel", "accelerometer", "timestamp_sample", "x", "y", "z", "m/s2", false},
      {"sensor_combined", "accelerometer", "timestamp", "accelerometer_m_s2[0]",
       "accelerometer_m_s2[1]", "accelerometer_m_s2[2]", "m/s2", true},
      {"sensor_gyro", "gyroscope", "timestamp_sample", "x", "y", "z", "rad/s", false},
      {"sensor_combined", "gyroscope", "timestamp", "gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]",
       "rad/s", true},
      // ArduPilot: ACC and GYR at SampleUS, IMU at TimeUS.
      {"IMU", "accelerometer", "TimeUS", "AccX", "AccY", "AccZ", "m/s2", true},
      {"ACC", "accelerometer", "SampleUS", "AccX", "AccY", "AccZ", "m/s2", true},
      {"IMU", "gyroscope", "TimeUS", "GyrX", "GyrY", "GyrZ", "rad/s", true},
      {"GYR", "gyroscope", "SampleUS", "GyrX", "GyrY", "GyrZ", "rad/s", true},
  };
  return kStreams;
}

namespace {

using internal::Format;

const KnownStream* Known(std::string_view topic, std::string_view sensor) {
  for (const KnownStream& k : KnownStreams()) {
    if (k.topic == topic && k.sensor == sensor) return &k;
  }
  return nullptr;
}

LogStreamInfo Describe(const internal::DecodedStream& s) {
  LogStreamInfo info;
  info.topic = s.topic;
  info.instance = s.instance;
  info.device_id = s.device_id;
  info.samples = s.messages;
  info.first_s = static_cast<double>(s.first_us) / 1e6;
  info.last_s = static_cast<double>(s.last_us) / 1e6;
  if (s.messages >= 2 && s.last_us > s.first_us) {
    info.rate_hz = static_cast<double>(s.messages - 1) / (info.last_s - info.first_s);
  }
  info.columns = s.columns;
  for (const KnownStream& k : KnownStreams()) {
    if (k.topic == s.topic) info.sensors.emplace_back(k.sensor);
  }
  return info;
}

// "sensor_accel instance 1 (device id 2424842, 1200 samples at 200 Hz)", for lists.
std::string Line(const internal::DecodedStream& s) {
  std::string out = Format("%s instance %d (", s.topic.c_str(), s.instance);
  if (s.device_id) out += Format("device id %llu, ", static_cast<unsigned long long>(*s.device_id));
  const LogStreamInfo info = Describe(s);
  out += Format("%zu samples", s.messages);
  if (info.rate_hz > 0) out += Format(" at %.4g Hz", info.rate_hz);
  return out + ")";
}

// Which column of `s` a columns option's entry names: a field's name, or its 1-based number.
std::size_t ColumnOf(const internal::DecodedStream& s, const std::string& entry,
                     const std::string& source) {
  const auto it = std::find(s.columns.begin(), s.columns.end(), entry);
  if (it != s.columns.end()) return std::size_t(it - s.columns.begin());
  std::size_t number = 0;
  bool digits = !entry.empty() && entry.size() < 6;
  for (char c : entry) {
    if (c < '0' || c > '9')
      digits = false;
    else
      number = number * 10 + std::size_t(c - '0');
  }
  if (digits && number >= 1 && number <= s.columns.size()) return number - 1;
  std::string fields;
  for (const std::string& c : s.columns) fields += (fields.empty() ? "" : ", ") + c;
  throw InputError(source, 0,
                   "the columns option names \"" + entry + "\", which " + s.topic +
                       " does not have (its fields: " + fields + ")");
}

}  // namespace

namespace internal {

namespace {

// The format's name for messages.
const char* FormatName(LogFormat format) {
  return format == LogFormat::kULog ? "PX4 ULog" : "ArduPilot DataFlash log";
}

// A binary log's format, from its first bytes in `in`.
LogFormat FormatOf(BinaryStream& in) {
  in.Need(16);
  return DetectLogFormat(std::string_view(reinterpret_cast<const char*>(in.data()),
                                          std::min<std::size_t>(in.available(), 16)));
}

DecodedLog Decode(BinaryStream& in, LogFormat format, const KeepStream& keep) {
  return format == LogFormat::kULog ? ReadULog(in, keep) : ReadDataFlash(in, keep);
}

// The time field of stream `s` when none is named: the known stream's, else the first of the
// formats' own that it has.
std::string DefaultTime(const DecodedStream& s, const KnownStream* known) {
  if (known != nullptr) return std::string(known->time);
  for (const char* name : {"timestamp_sample", "timestamp", "SampleUS", "TimeUS"}) {
    if (std::find(s.columns.begin(), s.columns.end(), name) != s.columns.end()) return name;
  }
  return "timestamp";
}

}  // namespace

InputData ReadNativeLog(BinaryStream& in, InputFile* file, const ReadOptions& options) {
  const std::string source = in.name();
  const LogFormat format = FormatOf(in);
  const std::string name = FormatName(format);
  if (options.kind == InputKind::kPositions) {
    throw InputError(source, 0, "a " + name + " is a raw log, not a positions file");
  }
  if (options.time_unit != TimeUnit::kAuto && options.time_unit != TimeUnit::kMicroseconds) {
    throw InputError(source, 0,
                     "a " + name +
                         "'s timestamps are in microseconds by its specification, not in " +
                         std::string(ToString(options.time_unit)));
  }
  Sha256 hash;
  if (options.fingerprint) in.Fingerprint(&hash);
  // Keep the topic asked for, or every stream of the sensor accelcal knows.
  const std::string_view sensor = NameOf(options.sensor);
  const auto keep = [&](const std::string& topic, int) {
    return options.topic.empty() ? Known(topic, sensor) != nullptr : topic == options.topic;
  };
  DecodedLog log = Decode(in, format, keep);
  in.Drain();
  if (options.fingerprint && file != nullptr) RequireUnchanged(*file);
  // The stream: the topic's (and instance's) with messages.
  std::vector<const DecodedStream*> candidates;
  for (const DecodedStream& s : log.streams) {
    if (!s.kept || s.messages == 0) continue;
    if (options.instance && static_cast<double>(s.instance) != *options.instance) continue;
    candidates.push_back(&s);
  }
  if (candidates.size() != 1) {
    std::string list;
    for (const DecodedStream& s : log.streams) {
      if (s.messages > 0 &&
          (options.topic.empty() ? Known(s.topic, sensor) != nullptr : s.topic == options.topic)) {
        list += "; " + Line(s);
      }
    }
    const std::string what = options.topic.empty() ? std::string(sensor) + " stream"
                                                   : "stream of topic " + options.topic;
    const std::string which =
        options.instance ? Format(" with instance %g", *options.instance) : std::string();
    if (candidates.empty()) {
      std::string topics;
      for (const DecodedStream& s : log.streams) {
        if (s.messages > 0) topics += (topics.empty() ? "" : ", ") + s.topic;
      }
      throw InputError(source, 0,
                       "no " + what + which + " with samples" +
                           (list.empty() ? " (its topics: " + topics + ")" : ":" + list.substr(1)));
    }
    throw InputError(source, 0,
                     "several " + what + "s:" + list.substr(1) +
                         "; choose one with the topic and instance options");
  }
  const DecodedStream& s = *candidates.front();
  // Its columns: the option's (x,y,z or time,x,y,z), else the known stream's fields and the
  // sample time (timestamp_sample when the topic has one: when the sensor sampled, not when the
  // message was published).
  std::size_t column[4];
  const KnownStream* known = Known(s.topic, sensor);
  if (!options.columns.empty()) {
    const std::size_t n = options.columns.size();
    if (n != 3 && n != 4) {
      throw InputError(source, 0, "the columns option takes 3 entries (x,y,z) or 4 (time,x,y,z)");
    }
    if (n == 3) column[0] = ColumnOf(s, DefaultTime(s, known), source);
    for (std::size_t i = 0; i < n; ++i) column[4 - n + i] = ColumnOf(s, options.columns[i], source);
  } else {
    if (known == nullptr) {
      throw InputError(source, 0,
                       "accelcal does not know which fields of " + s.topic +
                           " are the readings: name them with the columns option (x,y,z or "
                           "time,x,y,z)");
    }
    column[0] = ColumnOf(s, DefaultTime(s, known), source);
    column[1] = ColumnOf(s, std::string(known->x), source);
    column[2] = ColumnOf(s, std::string(known->y), source);
    column[3] = ColumnOf(s, std::string(known->z), source);
  }
  InputData data;
  data.kind = InputKind::kRaw;
  data.kind_reason = "a " + name + ": " + Line(s);
  RawLog& raw = data.raw;
  raw.source = source;
  const std::size_t width = s.columns.size();
  raw.time_s.reserve(s.messages);
  raw.samples.reserve(s.messages);
  raw.line.reserve(s.messages);
  for (std::size_t i = 0; i < s.messages; ++i) {
    const double* row = s.values.data() + i * width;
    raw.time_s.push_back(row[column[0]]);
    raw.samples.emplace_back(row[column[1]], row[column[2]], row[column[3]]);
    raw.line.push_back(static_cast<std::uint32_t>(std::min<std::size_t>(i + 1, UINT32_MAX)));
  }
  for (std::size_t i = 0; i < raw.samples.size(); ++i) {
    if (!raw.samples[i].allFinite() || !std::isfinite(raw.time_s[i])) {
      throw InputError(
          source, 0,
          Format("%s message %zu (byte %llu) holds a value that is not a finite "
                 "number",
                 s.topic.c_str(), i + 1, static_cast<unsigned long long>(s.offset[i])));
    }
  }
  if (log.truncated) raw.read_warning = *log.truncated;
  FinishRawLog(&raw, TimeUnit::kMicroseconds, options.rate_hz, s.columns[column[0]]);
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
    throw InputError(file.name(), 0,
                     "not a binary log (PX4 ULog, ArduPilot DataFlash): a text log's columns "
                     "are its header's");
  }
  internal::BinaryStream in(&file, std::move(head));
  const internal::DecodedLog log =
      internal::Decode(in, out.format, [](const std::string&, int) { return false; });
  out.bytes = log.bytes;
  for (const internal::DecodedStream& s : log.streams) out.streams.push_back(Describe(s));
  out.parameters = log.parameters;
  out.info = log.info;
  out.truncated = log.truncated;
  return out;
}

}  // namespace accelcal
