// Reading a calibration file's gyroscope (calibration_file_sections.hpp): its model, parameters,
// offsets over temperature, noise and diagnostics, checked as the accelerometer's are.
#include <cmath>

#include <Eigen/SVD>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "output/calibration_file_sections.hpp"

namespace accelcal::internal {

namespace {

Mat33 Matrix3(const Reader& r, const ordered_json& doc, const char* key) {
  if (!doc.contains(key) || !doc[key].is_array() || doc[key].size() != 3) {
    r.Fail(r.Key(key) + " must be a 3x3 array");
  }
  Mat33 m;
  for (int i = 0; i < 3; ++i) {
    const auto& row = doc[key][i];
    if (!row.is_array() || row.size() != 3) r.Fail(r.Key(key) + " must be a 3x3 array");
    for (int j = 0; j < 3; ++j) {
      m(i, j) = r.Number(row[j], r.Key(std::string(key) + "[" + std::to_string(i) + "][" +
                                       std::to_string(j) + "]"));
    }
  }
  return m;
}

// The gyroscope's `thermal`: its offsets over temperature (thermal.hpp's GyroThermalBias).
void ReadGyroThermal(const Reader& r, const ordered_json& doc, LoadedCalibration::Gyroscope& g) {
  const ordered_json& t = r.Object(doc, "thermal");
  const Reader in = r.Inside("thermal");
  GyroThermalBias bias;
  if (!t.contains("t_ref")) in.Fail(in.Key("t_ref") + " is missing");
  bias.t_ref_c = in.Number(t["t_ref"], in.Key("t_ref"));
  if (!t.contains("degree") || !t["degree"].is_number_unsigned() ||
      t["degree"].get<std::uint64_t>() > kMaxThermalDegree) {
    in.Fail(in.Key("degree") + " must be a whole number from 0 to " +
            std::to_string(kMaxThermalDegree));
  }
  const auto degree = t["degree"].get<std::size_t>();
  const std::string shape =
      " must be an array of " + std::to_string(degree) + " arrays of 3 numbers (its degree)";
  for (const char* key : {"coefficients", "std"}) {
    if (!t.contains(key) || !t[key].is_array() || t[key].size() != degree) {
      in.Fail(in.Key(key) + shape);
    }
    for (std::size_t d = 0; d < degree; ++d) {
      if (!t[key][d].is_array() || t[key][d].size() != 3) in.Fail(in.Key(key) + shape);
      for (int a = 0; a < 3; ++a) {
        const double v = in.Number(t[key][d][a], in.Key(key));
        if (key[0] == 'c') {
          if (a == 0) bias.coefficients.emplace_back(Vec3::Zero());
          bias.coefficients.back()(a) = v;
        } else if (!(v >= 0)) {
          in.Fail(in.Key(key) + " must not be negative");
        }
      }
    }
  }
  if (t.contains("covariance") && !t["covariance"].is_null()) {
    if (degree == 0) in.Fail(in.Key("covariance") + " must be null for degree 0");
    bias.covariance = ReadSquareCovariance(in, t, 3 * degree, "the offsets' coefficients");
  }
  g.thermal_range_c = ReadTemperatureRange(in, t, bias.t_ref_c);
  if (t.contains("temperature_source")) g.thermal_source = in.Text(t, "temperature_source");
  g.thermal = std::move(bias);
}

}  // namespace

LoadedCalibration::Gyroscope ReadGyroscope(const Reader& r, const ordered_json& doc) {
  LoadedCalibration::Gyroscope g;
  const std::optional<GyroModelKind> model =
      doc.contains("model") && doc["model"].is_string()
          ? GyroModelKindFromString(doc["model"].get<std::string>())
          : std::nullopt;
  if (!model) r.Fail(r.Key("model") + " must be \"linear\" or \"g-sensitive\"");
  g.model = *model;
  g.params.K = Matrix3(r, doc, "K");
  {  // singular to the precision of a double: its rates cannot be corrected
    const Vec3 sv = Eigen::JacobiSVD<Mat33>(g.params.K).singularValues();
    if (!(sv(2) > 1e-12 * sv(0))) r.Fail(r.Key("K") + " is singular (its rows dependent)");
  }
  g.params.bias = r.Vector3(doc, "bias");
  if (g.model == GyroModelKind::kGSensitive) {
    g.params.G = Matrix3(r, doc, "g_sensitivity");
  } else if (doc.contains("g_sensitivity") && !doc["g_sensitivity"].is_null()) {
    r.Fail(r.Key("g_sensitivity") + " must be null for the linear model");
  }
  if (doc.contains("units") && doc["units"].is_object() && doc["units"].contains("raw")) {
    g.raw_unit = r.Inside("units").Text(doc["units"], "raw");
  }
  if (doc.contains("source") && doc["source"].is_string()) {
    g.source = doc["source"].get<std::string>();
  }
  if (doc.contains("covariance") && !doc["covariance"].is_null()) {
    g.covariance =
        ReadSquareCovariance(r, doc, static_cast<std::size_t>(NumGyroParameters(g.model)),
                             "the " + std::string(ToString(g.model)) + " gyroscope model");
  }
  if (doc.contains("validation") && doc["validation"].is_object()) {
    g.heldout_rms_deg = r.Inside("validation").Nullable(doc["validation"], "heldout_rms_deg");
    g.rms_deg = r.Inside("validation").Nullable(doc["validation"], "rms_deg");
  }
  if (doc.contains("estimator")) g.estimator = r.Text(doc, "estimator");
  if (doc.contains("noise") && doc["noise"].is_object()) {
    const Reader rn = r.Inside("noise");
    g.rotation_scatter_ratio = rn.Nullable(doc["noise"], "rotation_scatter_ratio");
    if (g.rotation_scatter_ratio && !(*g.rotation_scatter_ratio > 0)) {
      rn.Fail(rn.Key("rotation_scatter_ratio") + " must be positive");
    }
    g.still_scatter_ratio = rn.Nullable(doc["noise"], "still_scatter_ratio");
    if (g.still_scatter_ratio && !(*g.still_scatter_ratio > 0)) {
      rn.Fail(rn.Key("still_scatter_ratio") + " must be positive");
    }
  }
  // The records the report plots, when present.
  const auto array = [&](const char* key) -> const ordered_json* {
    if (!doc.contains(key)) return nullptr;
    if (!doc[key].is_array()) r.Fail(r.Key(key) + " must be an array");
    return &doc[key];
  };
  if (const ordered_json* rotations = array("rotations")) {
    const Reader in = r.Inside("rotations[]");
    for (const ordered_json& t : *rotations) {
      if (!t.is_object()) r.Fail(r.Key("rotations") + " must hold objects");
      LoadedCalibration::Gyroscope::Rotation rotation;
      for (const auto& [key, value] :
           {std::pair("from", &rotation.from), std::pair("to", &rotation.to),
            std::pair("residual_deg", &rotation.residual_deg)}) {
        if (!t.contains(key)) in.Fail(in.Key(key) + " is missing");
        *value = in.Number(t[key], in.Key(key));
      }
      rotation.heldout_deg = in.Nullable(t, "heldout_deg");
      rotation.turned_deg = in.Nullable(t, "turned_deg");
      // Positions are counted from 1; angles and their errors are not negative.
      for (const auto& [key, value] :
           {std::pair("from", rotation.from), std::pair("to", rotation.to)}) {
        if (!(value >= 1 && value == std::floor(value))) {
          in.Fail(in.Key(key) + " must be a position's number (1, 2, ...)");
        }
      }
      for (const auto& [key, value] :
           {std::pair("residual_deg", std::optional<double>(rotation.residual_deg)),
            std::pair("heldout_deg", rotation.heldout_deg),
            std::pair("turned_deg", rotation.turned_deg)}) {
        if (value && !(*value >= 0)) in.Fail(in.Key(key) + " must not be negative");
      }
      g.rotations.push_back(rotation);
    }
  }
  if (const ordered_json* stills = array("stills")) {
    const Reader in = r.Inside("stills[]");
    for (const ordered_json& st : *stills) {
      if (!st.is_object()) r.Fail(r.Key("stills") + " must hold objects");
      const Vec3 mean = in.Vector3(st, "mean_raw");
      // A position the gyro turned throughout (`still` false) has no still rate.
      bool still = true;
      if (st.contains("still")) {
        if (!st["still"].is_boolean()) in.Fail(in.Key("still") + " must be true or false");
        still = st["still"].get<bool>();
      }
      g.still_mean_raw.push_back(still ? mean : Vec3::Constant(std::nan("")));
    }
  }
  if (doc.contains("thermal")) ReadGyroThermal(r, doc, g);
  return g;
}

}  // namespace accelcal::internal
