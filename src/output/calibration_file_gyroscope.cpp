// The gyroscope's section of a calibration file (`sensors.gyroscope`), described once
// (section_io.hpp): CalibrationToJson writes it, ParseCalibrationJson reads it back into the
// UnitGyroscope calibrate made, and Python pickles it.
#include <algorithm>
#include <cmath>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "output/calibration_file_sections.hpp"
#include "output/section_io.hpp"

namespace accelcal::internal {

// A struct that gains a field must have it in its description below (or a line in UnitGyroscope's
// comment saying why the file does not hold it): these sizes (x86-64, libstdc++) are those of the
// structs the descriptions were written for.
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(UnitGyroscope) == 1560, "UnitGyroscope changed: update its description");
static_assert(sizeof(GyroRotation) == 104, "GyroRotation changed: update its description");
static_assert(sizeof(GyroStillSpan) == 56, "GyroStillSpan changed: update its description");
static_assert(sizeof(GyroTimeOffset) == 40, "GyroTimeOffset changed: update its description");
static_assert(sizeof(GyroThermal) == 176, "GyroThermal changed: update its description");
static_assert(sizeof(GyroThermalBias) == 56, "GyroThermalBias changed: update its description");
static_assert(sizeof(Summary) == 112, "Summary changed: update the gyroscope's solver record");
#endif

namespace {

// Its solver's record: the termination and costs (converged follows from the termination).
template <typename Io>
void DescribeSolver(Io& io, Summary& s) {
  io.Whole("iterations", s.iterations);
  if constexpr (Io::kReading) {
    if (s.iterations < 0) io.Fail(io.Key("iterations") + " must not be negative");
  }
  io.Derived("converged", [&] { return s.converged(); });
  io.Choice("termination", s.termination);
  io.Text("termination_message", s.termination_message);
  io.Number("initial_cost", s.initial_cost);
  io.Number("cost", s.final_cost);
}

// `thermal`: the offsets over temperature (degree 0: asked for, none found) and the
// temperatures they were fitted over, to which they are held.
template <typename Io>
void DescribeThermal(Io& io, GyroThermal& t) {
  GyroThermalBias& b = t.bias;
  io.Derived("equation", [] {
    return "b(T) = bias + sum_d coefficients[d-1] (T - t_ref)^d, T in degC: the offsets over "
           "temperature, the rest of the model at t_ref; coefficients[d-1] in raw per K^d, T held "
           "to temperature_range";
  });
  io.Number("t_ref", b.t_ref_c, Need::kRequired);
  io.Text("temperature_source", t.temperature_source);
  std::size_t degree = b.coefficients.size();
  io.Count("degree", degree, Need::kRequired);
  io.Text("degree_reason", t.reason);
  io.Interval("temperature_range", t.range_c, Need::kRequired);
  io.Vectors("coefficients", b.coefficients, Need::kRequired);
  io.Derived("std", [&] {
    ordered_json sd = ordered_json::array();
    if (b.covariance.rows() < static_cast<Eigen::Index>(3 * degree)) return ordered_json(nullptr);
    for (std::size_t d = 0; d < degree; ++d) {
      Vec3 s;
      for (int a = 0; a < 3; ++a) {
        const auto i = static_cast<Eigen::Index>(3 * d + static_cast<std::size_t>(a));
        s(a) = std::sqrt(std::max(0.0, b.covariance(i, i)));
      }
      sd.push_back(SectionWriter::Json(s));
    }
    return sd;
  });
  if constexpr (Io::kReading) {
    if (degree > static_cast<std::size_t>(kMaxThermalDegree)) {
      io.Fail(io.Key("degree") + " must be a whole number from 0 to " +
              std::to_string(kMaxThermalDegree));
    }
    const std::string shape =
        " must be an array of " + std::to_string(degree) + " arrays of 3 numbers (its degree)";
    if (b.coefficients.size() != degree) io.Fail(io.Key("coefficients") + shape);
    // The coefficients' 1σ: recomputed when written, but checked as read.
    std::vector<Vec3> sd;
    io.Vectors("std", sd, Need::kRequired);
    for (const Vec3& v : sd) {
      if (!(v.minCoeff() >= 0)) io.Fail(io.Key("std") + " must not be negative");
    }
    if (sd.size() != degree) io.Fail(io.Key("std") + shape);
  }
  if (degree > 0) {
    io.Covariance(b.covariance, 3 * degree, "the offsets' coefficients");
    if constexpr (Io::kReading) {
      if (b.covariance.size() == 0) {
        io.Fail(io.Key("covariance") + " must be a " + std::to_string(3 * degree) + "x" +
                std::to_string(3 * degree) + " array (the offsets' coefficients)");
      }
    }
  } else {
    io.Null("covariance", "for degree 0");
  }
  io.Number("scatter_ratio", t.scatter_ratio);
  io.MaybeNumber("heldout_rms_raw", t.heldout_rms_raw);
  io.Numbers("temperatures", t.temperatures_c);
  if constexpr (Io::kReading) CheckTemperatureRange(io.reader(), t.range_c, b.t_ref_c);
}

// A turn between two still positions: the positions it joins, its samples, the angles, its
// residual and its held-out error.
template <typename Io>
void DescribeRotation(Io& io, GyroRotation& r) {
  io.PositionNumber("from", r.from, Need::kRequired);
  io.PositionNumber("to", r.to, Need::kRequired);
  io.Count("first_sample", r.first_sample);
  io.Count("last_sample", r.last_sample);
  io.Number("duration_s", r.duration_s);
  io.Number("angle_deg", r.angle_deg);
  io.MaybeNumber("turned_deg", r.turned_deg);
  io.Number("turned_std_deg", r.turned_std_deg);
  io.Number("residual_deg", r.residual_deg, Need::kRequired);
  io.MaybeNumber("heldout_deg", r.heldout_deg);
  io.MaybeNumber("statistic", r.statistic);
  io.MaybeNumber("threshold", r.threshold);
  io.Flag("flagged", r.flagged);
  io.Derived("excluded", [] { return false; });
  if constexpr (Io::kReading) {  // angles, durations and their errors are not negative
    for (const auto& [key, value] :
         {std::pair("residual_deg", r.residual_deg), std::pair("heldout_deg", r.heldout_deg),
          std::pair("turned_deg", r.turned_deg), std::pair("turned_std_deg", r.turned_std_deg),
          std::pair("duration_s", r.duration_s), std::pair("angle_deg", r.angle_deg)}) {
      if (value < 0) io.Fail(io.Key(key) + " must not be negative");
    }
    if (r.first_sample > r.last_sample) {
      io.Fail(io.Key("first_sample") + " must not be after " + io.Key("last_sample"));
    }
  }
}

template <typename Io>
void DescribeStill(Io& io, GyroStillSpan& s, std::size_t index) {
  std::size_t number = index + 1;
  io.Count("position", number);
  io.Count("first_sample", s.first_sample);
  io.Count("last_sample", s.last_sample);
  if constexpr (Io::kReading) {
    if (number != index + 1) {
      io.Fail(io.Key("position") + " must be its place in the list (" + std::to_string(index + 1) +
              ")");
    }
    if (s.first_sample > s.last_sample) {
      io.Fail(io.Key("first_sample") + " must not be after " + io.Key("last_sample"));
    }
  }
  io.Vector("mean_raw", s.mean_raw, Need::kRequired);
  io.Number("turned_outside_deg", s.turned_outside_deg);
  io.Flag("still", s.still);
}

// The whole section, in the file's order. `force_unit`: the accelerometer's, in which G is.
template <typename Io>
void DescribeGyroscope(Io& io, UnitGyroscope& g, ForceUnit force_unit) {
  io.Choice("model", g.model, Need::kRequired);
  io.Text("model_reason", g.model_reason);
  io.Choice("estimator", g.estimator, Need::kRequired);
  io.Object("units", [&](auto& u) {
    u.Text("raw", g.raw_unit);
    u.Choice("raw_declared", g.unit);
    u.Derived("rate", [] { return "rad/s"; });
    u.Derived("specific_force", [&] { return std::string(ToString(force_unit)); });
  });
  io.Derived("equation", [] {
    return "w_raw = K w + b + G f; w_raw raw, w the body rate [rad/s] and f the specific force in "
           "the accelerometer's body frame";
  });
  io.Matrix("K", g.params.K, Need::kRequired);
  io.Vector("bias", g.params.bias, Need::kRequired);
  const bool g_sensitive = g.model == GyroModelKind::kGSensitive;
  if (g_sensitive) {
    io.Matrix("g_sensitivity", g.params.G, Need::kRequired);
  } else {
    io.Null("g_sensitivity", "for the linear model");
  }
  io.Derived("parameter_order", [&] {
    ordered_json order = ordered_json::array();
    for (const GyroParameterSlot& s : GyroParameterSlots(g.model))
      order.push_back(std::string(s.name));
    return order;
  });
  io.Derived("std", [&] {
    if (g.covariance.size() == 0) return ordered_json(nullptr);
    const GyroParameters sd =
        UnpackGyro(g.covariance.diagonal().cwiseMax(0.0).cwiseSqrt(), g.model);
    ordered_json out;
    out["K"] = SectionWriter::Json(sd.K);
    out["bias"] = SectionWriter::Json(sd.bias);
    out["g_sensitivity"] = g_sensitive ? SectionWriter::Json(sd.G) : ordered_json(nullptr);
    return out;
  });
  io.Covariance(g.covariance, static_cast<std::size_t>(NumGyroParameters(g.model)),
                "the " + std::string(ToString(g.model)) + " gyroscope model");
  io.Derived("engineering", [&] {
    ordered_json scale = ordered_json::array();
    for (int i = 0; i < 3; ++i) scale.push_back(g.params.K.row(i).norm());
    return ordered_json{{"scale_factor_raw_per_rad_s", scale}};
  });
  io.Object("noise", [&](auto& n) {
    n.Vector("sigma_raw_per_sample", g.noise_sigma_raw);
    n.MaybeNumber("still_scatter_ratio", g.still_scatter_ratio);
    n.MaybeNumber("rotation_scatter_ratio", g.rotation_scatter_ratio);
    n.MaybeNumber("accelerometer_scatter_ratio", g.accel_scatter_ratio);
    if constexpr (Io::kReading) {
      for (const auto& [key, value] :
           {std::pair("rotation_scatter_ratio", g.rotation_scatter_ratio),
            std::pair("still_scatter_ratio", g.still_scatter_ratio)}) {
        if (!std::isnan(value) && !(value > 0)) n.Fail(n.Key(key) + " must be positive");
      }
    }
  });
  io.List("stills", g.still_spans,
          [](auto& s, GyroStillSpan& span, std::size_t i) { DescribeStill(s, span, i); });
  bool thermal = g.thermal.has_value();
  if constexpr (Io::kReading) g.thermal.emplace();
  io.MaybeObject(
      "thermal", thermal, [&](auto& t) { DescribeThermal(t, *g.thermal); },
      /*null_when_absent=*/false);
  if constexpr (Io::kReading) {
    if (!thermal) g.thermal.reset();
  }
  bool lagged = g.time_offset.has_value();
  if constexpr (Io::kReading) g.time_offset.emplace();
  io.MaybeObject("time_offset", lagged, [&](auto& t) {
    t.Number("lag_s", g.time_offset->lag_s, Need::kRequired);
    t.Number("std_s", g.time_offset->std_s, Need::kRequired);
    t.Count("turns", g.time_offset->turns, Need::kRequired);
    t.Flag("at_limit", g.time_offset->at_limit, Need::kRequired);
    if constexpr (Io::kReading) {
      if (g.time_offset->std_s < 0) t.Fail(t.Key("std_s") + " must not be negative");
    }
  });
  if constexpr (Io::kReading) {
    if (!lagged) g.time_offset.reset();
  }
  io.List("rotations", g.rotations,
          [](auto& s, GyroRotation& r, std::size_t) { DescribeRotation(s, r); });
  bool earth = g.latitude_deg.has_value();
  double latitude = g.latitude_deg.value_or(0);
  io.MaybeObject("earth_rate", earth, [&](auto& e) {
    e.Number("latitude_deg", latitude, Need::kRequired);
    e.Number("vertical_rad_s", g.earth_rate_vertical_rad_s, Need::kRequired);
    e.Number("horizontal_rad_s", g.earth_rate_horizontal_rad_s, Need::kRequired);
    if constexpr (Io::kReading) {
      if (!(std::abs(latitude) <= 90)) e.Fail(e.Key("latitude_deg") + " must be from -90 to 90");
    }
  });
  if constexpr (Io::kReading)
    g.latitude_deg = earth ? std::optional<double>(latitude) : std::nullopt;
  io.Object("validation", [&](auto& v) {
    v.MaybeNumber("rms_deg", g.rms_deg);
    v.MaybeNumber("heldout_rms_deg", g.heldout_rms_deg);
  });
  io.Object("solver", [&](auto& s) { DescribeSolver(s, g.summary); });
  io.Text("source", g.source);
  if constexpr (Io::kReading) {
    CheckInvertible(io.reader(), g.params.K, "K");
    if (g.estimator == GyroEstimator::kImuTk && g.model != GyroModelKind::kLinear) {
      io.Fail(io.Key("estimator") + " imutk fits the linear model only, not " + io.Key("model") +
              " " + std::string(ToString(g.model)));
    }
  }
}

}  // namespace

ordered_json GyroscopeSection(const UnitGyroscope& g, ForceUnit force_unit) {
  ordered_json doc = ordered_json::object();
  SectionWriter io(&doc);
  DescribeGyroscope(io, const_cast<UnitGyroscope&>(g), force_unit);  // the writer only reads it
  return doc;
}

UnitGyroscope ReadGyroscope(const Reader& r, const ordered_json& doc) {
  UnitGyroscope g;
  g.raw_unit.clear();  // a file without `units.raw` names no raw unit
  // What a file that lacks a record did not state: not known (NaN), not the defaults.
  g.rms_deg = g.still_scatter_ratio = g.rotation_scatter_ratio = g.accel_scatter_ratio =
      std::nan("");
  SectionReader io(r, doc);
  DescribeGyroscope(io, g, ForceUnit::kMetersPerSecond2);
  return g;
}

}  // namespace accelcal::internal

namespace accelcal {

nlohmann::ordered_json GyroscopeToJson(const UnitGyroscope& gyroscope, ForceUnit force_unit) {
  return internal::GyroscopeSection(gyroscope, force_unit);
}

UnitGyroscope GyroscopeFromJson(const nlohmann::ordered_json& section, const std::string& source) {
  return internal::ReadGyroscope(internal::Reader(source, ""), section);
}

}  // namespace accelcal
