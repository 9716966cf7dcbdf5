// Reading what `accelcal noise --json` wrote (noise_file.hpp).
#include "accelcal/noise_file.hpp"

#include "accelcal/gravity.hpp"
#include "output/json_reader.hpp"

namespace accelcal {

namespace {

using internal::ordered_json;
using internal::Reader;

SensorNoiseDensities ReadSensor(const Reader& top, const ordered_json& doc, const char* name,
                                double rate_hz) {
  const Reader r = top.Inside(name);
  const ordered_json& sensor = top.Object(doc, name);
  const std::string unit = r.Text(sensor, "unit");
  double si = 0;  // SI units per the file's
  if (std::string(name) == "accelerometer") {
    if (unit == "m/s2") si = 1;
    if (unit == "g") si = kStandardGravity_ms2;
  } else if (unit == "rad/s") {
    si = 1;
  }
  if (si == 0) {
    r.Fail(r.Key("unit") + " is '" + unit +
           "': an estimator takes densities in m/s2 and rad/s; analyse the log with "
           "a calibration (accelcal noise --calibration CAL.json)");
  }
  SensorNoiseDensities out;
  if (!sensor.contains("samples") || !sensor["samples"].is_number_unsigned()) {
    r.Fail(r.Key("samples") + " must be a whole number");
  }
  out.duration_s = static_cast<double>(sensor["samples"].get<std::uint64_t>()) / rate_hz;
  if (!sensor.contains("axes") || !sensor["axes"].is_array() || sensor["axes"].size() != 3) {
    r.Fail(r.Key("axes") + " must be an array of the 3 axes");
  }
  for (int a = 0; a < 3; ++a) {
    const ordered_json& axis = sensor["axes"][static_cast<std::size_t>(a)];
    const Reader ra = r.Inside("axes[" + std::to_string(a) + "]");
    // The axes in the order x, y, z: an estimator's per-axis values are written in that order.
    const std::string expected(1, static_cast<char>('x' + a));
    if (!axis.is_object() || !axis.contains("axis") || axis["axis"] != expected) {
      ra.Fail(ra.Key("axis") + " must be \"" + expected + "\" (the axes in the order x, y, z)");
    }
    const ordered_json& terms = ra.Object(axis, "terms");
    const Reader rt = ra.Inside("terms");
    const auto term = [&](const char* key) -> const ordered_json& { return rt.Object(terms, key); };
    const ordered_json& white = term("white");
    const Reader rw = rt.Inside("white");
    if (!white.contains("resolved") || !white["resolved"].is_boolean() ||
        !white["resolved"].get<bool>()) {
      rw.Fail(rw.Key("resolved") + " is not true: the log does not resolve this axis' white noise");
    }
    out.white(a) = si * rw.Number(white["value"], rw.Key("value"));
    const ordered_json& walk = term("random_walk");
    const Reader rk = rt.Inside("random_walk");
    if (!walk.contains("resolved") || !walk["resolved"].is_boolean()) {
      rk.Fail(rk.Key("resolved") + " must be true or false");
    }
    out.random_walk_resolved[static_cast<std::size_t>(a)] = walk["resolved"].get<bool>();
    out.random_walk(a) =
        si * (walk["resolved"].get<bool>() ? rk.Number(walk["value"], rk.Key("value"))
                                           : rk.Number(walk["high"], rk.Key("high")));
    if (!(out.white(a) > 0)) rw.Fail(rw.Key("value") + " must be positive");
    if (!(out.random_walk(a) > 0)) {
      // An estimator weighs the bias's change by 1 / K²: a K of 0 pins the bias for ever.
      rk.Fail(rk.Key(walk["resolved"].get<bool>() ? "value" : "high") +
              " must be positive: the random walk (or its upper bound)");
    }
  }
  return out;
}

}  // namespace

ImuNoise ParseNoiseJson(const std::string& text, const std::string& source) {
  const ordered_json doc = internal::ParseWithoutDuplicateKeys(text, source);
  const Reader r(source, "");
  if (!doc.is_object() || !doc.contains("model") || !doc.contains("accelerometer")) {
    r.Fail("not the output of accelcal noise --json (no 'model' and 'accelerometer')");
  }
  const std::string verdict = r.Text(doc, "verdict");
  if (verdict != "passed" && verdict != "failed") {
    r.Fail(r.Key("verdict") + " must be \"passed\" or \"failed\"");
  }
  if (verdict != "passed") {
    r.Fail(r.Key("verdict") + " is '" + verdict +
           "': the noise terms failed their checks and are not a result (see the notes there)");
  }
  ImuNoise out;
  out.source = source;
  out.log = r.Text(doc, "source");
  out.rate_hz = r.Number(doc["rate_hz"], r.Key("rate_hz"));
  if (!(out.rate_hz > 0)) r.Fail(r.Key("rate_hz") + " must be positive");
  out.accelerometer = ReadSensor(r, doc, "accelerometer", out.rate_hz);
  if (doc.contains("gyroscope")) out.gyroscope = ReadSensor(r, doc, "gyroscope", out.rate_hz);
  return out;
}

}  // namespace accelcal
