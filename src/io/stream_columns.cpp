// A decoded stream's columns (stream_columns.hpp): the streams accelcal knows by their type and
// which of their fields are a sensor's readings, or the fields the columns option names.
#include "io/stream_columns.hpp"

#include <algorithm>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/ros_topics.hpp"

namespace accelcal {

namespace {

// A type's name as the table holds it: ROS 2's "sensor_msgs/msg/Imu" is ROS 1's "sensor_msgs/Imu".
std::string TableName(std::string_view type) {
  std::string name(type);
  if (const std::size_t msg = name.find("/msg/"); msg != std::string::npos) name.erase(msg, 4);
  return name;
}

}  // namespace

const std::vector<KnownStream>& KnownStreams() {
  static const std::vector<KnownStream> kStreams = {
      // PX4: sampled at timestamp_sample where the topic has one.
      {"sensor_accel",
       "accelerometer",
       "timestamp_sample",
       "x",
       "y",
       "z",
       "m/s2",
       false,
       KnownStream::Packing::kSample,
       {},
       {},
       "temperature"},
      {"sensor_combined", "accelerometer", "timestamp", "accelerometer_m_s2[0]",
       "accelerometer_m_s2[1]", "accelerometer_m_s2[2]", "m/s2", true},
      {"sensor_gyro",
       "gyroscope",
       "timestamp_sample",
       "x",
       "y",
       "z",
       "rad/s",
       false,
       KnownStream::Packing::kSample,
       {},
       {},
       "temperature"},
      {"sensor_combined", "gyroscope", "timestamp", "gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]",
       "rad/s", true},
      // PX4's FIFO topics: the driver's every sample, packed (SDLOG_PROFILE's raw FIFO bits).
      {"sensor_accel_fifo", "accelerometer", "timestamp_sample", "x", "y", "z", "m/s2", false,
       KnownStream::Packing::kFifo},
      {"sensor_gyro_fifo", "gyroscope", "timestamp_sample", "x", "y", "z", "rad/s", false,
       KnownStream::Packing::kFifo},
      // vehicle_imu: integrated over its interval, after the calibration in force.
      {"vehicle_imu", "accelerometer", "timestamp_sample", "delta_velocity[0]", "delta_velocity[1]",
       "delta_velocity[2]", "m/s2", true, KnownStream::Packing::kDelta, "delta_velocity_dt"},
      {"vehicle_imu", "gyroscope", "timestamp_sample", "delta_angle[0]", "delta_angle[1]",
       "delta_angle[2]", "rad/s", true, KnownStream::Packing::kDelta, "delta_angle_dt"},
      // ArduPilot: ACC and GYR at SampleUS, IMU at TimeUS.
      {"IMU",
       "accelerometer",
       "TimeUS",
       "AccX",
       "AccY",
       "AccZ",
       "m/s2",
       true,
       KnownStream::Packing::kSample,
       {},
       {},
       "T"},
      {"ACC", "accelerometer", "SampleUS", "AccX", "AccY", "AccZ", "m/s2", true},
      {"IMU",
       "gyroscope",
       "TimeUS",
       "GyrX",
       "GyrY",
       "GyrZ",
       "rad/s",
       true,
       KnownStream::Packing::kSample,
       {},
       {},
       "T"},
      {"GYR", "gyroscope", "SampleUS", "GyrX", "GyrY", "GyrZ", "rad/s", true},
      // ROS: a driver's message, stamped when sampled (REP 145 asks for the sensor's own frame,
      // without the driver's corrections).
      // A field's covariance[0] = -1 marks it not measured.
      {"sensor_msgs/Imu",
       "accelerometer",
       "header.stamp",
       "linear_acceleration.x",
       "linear_acceleration.y",
       "linear_acceleration.z",
       "m/s2",
       false,
       KnownStream::Packing::kSample,
       {},
       "linear_acceleration_covariance[0]"},
      {"sensor_msgs/Imu",
       "gyroscope",
       "header.stamp",
       "angular_velocity.x",
       "angular_velocity.y",
       "angular_velocity.z",
       "rad/s",
       false,
       KnownStream::Packing::kSample,
       {},
       "angular_velocity_covariance[0]"},
  };
  return kStreams;
}

std::vector<std::string_view> KnownSensors(std::string_view type) {
  const std::string name = TableName(type);
  std::vector<std::string_view> out;
  for (const KnownStream& k : KnownStreams()) {
    if (k.type == name) out.push_back(k.sensor);
  }
  return out;
}

namespace internal {

const KnownStream* Known(std::string_view type, std::string_view sensor) {
  const std::string name = TableName(type);
  for (const KnownStream& k : KnownStreams()) {
    if (k.type == name && k.sensor == sensor) return &k;
  }
  return nullptr;
}

std::string Shown(std::string_view name) { return internal::VisibleLine(name); }

std::string Fields(const DecodedStream& s) {
  std::string out;
  for (const std::string& c : *s.columns) out += (out.empty() ? "" : ", ") + Shown(c);
  return out;
}

std::optional<std::size_t> Find(const DecodedStream& s, std::string_view name) {
  const auto it = std::find(s.columns->begin(), s.columns->end(), name);
  if (it == s.columns->end()) return std::nullopt;
  return std::size_t(it - s.columns->begin());
}

namespace {

// Which column of `s` a columns option's entry names: a field's name, or its 1-based number.
std::size_t ColumnOf(const DecodedStream& s, const std::string& entry, const std::string& source,
                     const char* option = "the columns option") {
  if (const std::optional<std::size_t> c = Find(s, entry)) return *c;
  std::size_t number = 0;
  bool digits = !entry.empty() && entry.size() < 6;
  for (char c : entry) {
    if (c < '0' || c > '9') {
      digits = false;
    } else {
      number = number * 10 + std::size_t(c - '0');
    }
  }
  if (digits && number >= 1 && number <= s.columns->size()) return number - 1;
  throw InputError(source, 0,
                   std::string(option) + " names \"" + Shown(entry) + "\", which " +
                       Shown(s.topic) + " does not have (its fields: " + Fields(s) + ")");
}

}  // namespace

bool IsMicrosecondColumn(const DecodedStream& s, std::size_t c) {
  if (s.microseconds) {
    return std::find(s.microseconds->begin(), s.microseconds->end(), c) != s.microseconds->end();
  }
  const std::string& name = (*s.columns)[c];
  return std::find(std::begin(kMicrosecondFields), std::end(kMicrosecondFields), name) !=
         std::end(kMicrosecondFields);
}

Chosen Choose(const DecodedStream& s, const ReadOptions& options, const KnownStream* known,
              const std::string& source) {
  Chosen out;
  if (!options.columns.empty()) {
    const std::size_t n = options.columns.size();
    if (n != 3 && n != 4) {
      throw InputError(source, 0, "the columns option takes 3 entries (x,y,z) or 4 (time,x,y,z)");
    }
    if (n == 4) {
      out.time = ColumnOf(s, options.columns[0], source);
    } else if (known != nullptr) {
      out.time = Find(s, known->time);
    } else if (s.microseconds) {
      for (const char* name : {"header.stamp", kLogTime}) {
        if ((out.time = Find(s, name)) && IsMicrosecondColumn(s, *out.time)) break;
        out.time.reset();
      }
    } else {
      for (const char* name : kMicrosecondFields) {
        if ((out.time = Find(s, name))) break;
      }
    }
    for (std::size_t a = 0; a < 3; ++a)
      out.axis[a] = ColumnOf(s, options.columns[n - 3 + a], source);
  } else {
    if (known == nullptr) {
      throw InputError(source, 0,
                       "accelcal does not know which fields of " + Shown(s.topic) +
                           " are the readings: name them with the columns option (x,y,z or "
                           "time,x,y,z)");
    }
    // A field the known stream should have (an older firmware's log may not).
    const auto field = [&](std::string_view want) {
      if (const std::optional<std::size_t> c = Find(s, want)) return *c;
      throw InputError(source, 0,
                       Shown(s.topic) + " has no field " + std::string(want) +
                           " (its fields: " + Fields(s) +
                           "): name its time and readings with the columns option "
                           "(time,x,y,z, or x,y,z and the rate option)");
    };
    out.time = field(known->time);
    out.packing = known->packing;
    if (known->packing == KnownStream::Packing::kFifo) {
      // The arrays x[i], y[i], z[i]: as long as the log's format has them.
      const auto element = [&](std::string_view base, std::size_t i) {
        return std::string(base) + "[" + std::to_string(i) + "]";
      };
      out.axis[0] = field(element(known->x, 0));
      out.axis[1] = field(element(known->y, 0));
      out.axis[2] = field(element(known->z, 0));
      out.extra = {field("dt"), field("scale"), field("samples")};
      while (Find(s, element(known->x, out.fifo)) && Find(s, element(known->y, out.fifo)) &&
             Find(s, element(known->z, out.fifo))) {
        ++out.fifo;
      }
      for (std::string_view base : {known->x, known->y, known->z}) {
        for (std::size_t i = 1; i < out.fifo; ++i) out.extra.push_back(field(element(base, i)));
      }
    } else {
      out.axis[0] = field(known->x);
      out.axis[1] = field(known->y);
      out.axis[2] = field(known->z);
      if (known->packing == KnownStream::Packing::kDelta) out.extra = {field(known->interval)};
      if (!known->unmeasured.empty()) out.unmeasured = Find(s, known->unmeasured);
    }
  }
  if (options.temperature.empty()) {
    if (known != nullptr && !known->temperature.empty())
      out.temperature = Find(s, known->temperature);
  } else if (options.temperature != "none") {
    out.temperature = ColumnOf(s, options.temperature, source, "the temperature option");
  }
  std::vector<std::size_t> all(std::begin(out.axis), std::end(out.axis));
  if (out.time) all.insert(all.begin(), *out.time);

  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (all[i] == all[j]) {
        throw InputError(source, 0,
                         "the columns option reads the field " + Shown((*s.columns)[all[i]]) +
                             " twice: each of time, x, y, z needs its own");
      }
    }
  }
  if (out.temperature && std::find(all.begin(), all.end(), *out.temperature) != all.end()) {
    if (options.temperature.empty()) {
      out.temperature.reset();  // the known field, chosen as a reading: no temperature
    } else {
      throw InputError(source, 0,
                       "the temperature option names the field " +
                           Shown((*s.columns)[*out.temperature]) +
                           ", which is read as the time or a reading: each needs its own");
    }
  }
  return out;
}

std::vector<std::size_t> Stored(const Chosen& c) {
  std::vector<std::size_t> out;
  if (c.time) out.push_back(*c.time);
  out.insert(out.end(), std::begin(c.axis), std::end(c.axis));
  out.insert(out.end(), c.extra.begin(), c.extra.end());
  if (c.temperature) out.push_back(*c.temperature);
  if (c.unmeasured) out.push_back(*c.unmeasured);
  return out;
}

}  // namespace internal

}  // namespace accelcal
