// What a unit's calibration may be asked for (calibrate_unit.hpp): every rule between the options
// of `calibrate`, stated once, with the options marked {{name}} for each edge to name in its own
// words.
#include <algorithm>
#include <stdexcept>

#include "accelcal/calibrate_unit.hpp"
#include "accelcal/known_orientation.hpp"
#include "accelcal/names.hpp"
#include "core/text_format.hpp"
#include "pipeline/unit_options.hpp"

namespace accelcal {
namespace {

using internal::Format;

// The methods and starts an orientation-free fit takes (known-orientation and a given start are
// the library's, chosen by other means).
constexpr SolverMethod kOrientationFreeMethods[] = {
    SolverMethod::kJoint,   SolverMethod::kTwoStep,     SolverMethod::kNewtonLagrange,
    SolverMethod::kModulus, SolverMethod::kModulusNorm, SolverMethod::kEllipsoid};
constexpr Initialization kInitializations[] = {Initialization::kAuto, Initialization::kEllipsoidFit,
                                               Initialization::kNormalizedReadings};

template <typename T, std::size_t N>
bool OneOf(T value, const T (&allowed)[N]) {
  return std::find(std::begin(allowed), std::end(allowed), value) != std::end(allowed);
}

template <typename T, std::size_t N>
std::string NotOneOf(const char* option, T value, const T (&allowed)[N]) {
  std::string list;
  for (T a : allowed) list += (list.empty() ? "" : ", ") + std::string(NameOf(a));
  return std::string("{{") + option + "}}: '" + std::string(NameOf(value)) + "' is not one of " +
         list;
}

std::optional<std::string> GyroProblem(const UnitRequest& r) {
  const bool known = !r.orientations.empty();
  const GyroEstimator estimator = GyroEstimatorOf(r);
  if (known && estimator == GyroEstimator::kJoint) {
    return "{{gyro_estimator}} joint fits every position's gravity direction, which "
           "{{orientations}} gives: the gyroscope is fitted on top of the known-orientation "
           "calibration (two-stage)";
  }
  if (r.thermal && estimator == GyroEstimator::kJoint) {
    return "{{gyro_estimator}} joint refits the accelerometer's parameters as constants, which "
           "{{thermal}}'s are not: the gyroscope is fitted on top of the calibration over "
           "temperature (two-stage, the default with {{thermal}})";
  }
  if ((r.gyro_thermal || r.gyro_thermal_auto) && !r.thermal) {
    return "{{gyro_thermal}} is the gyroscope's offsets over temperature, fitted with "
           "{{thermal}}: give it too";
  }
  if (auto why = GyroOptionsOf(r).Validate()) return why;
  const std::string first = r.inputs.empty() ? std::string() : r.inputs.front();
  return GyroInputProblem(first, r.load.read.columns, *r.gyro);
}

std::optional<std::string> TemperaturesProblem(const UnitRequest& r) {
  if (r.temperatures_c.empty()) return std::nullopt;
  if (!r.thermal) return "{{temperatures}} are for {{thermal}}: give it too";
  const std::size_t files = r.inputs.size();
  if (r.temperatures_c.size() != files) {
    return Format("{{temperatures}}: %zu given for %zu input file%s: one per file",
                  r.temperatures_c.size(), files, files == 1 ? "" : "s");
  }
  for (double t : r.temperatures_c) {
    if (!InTemperatureRange(t)) {
      return Format("{{temperatures}}: %g is outside %g to %g degC", t, kTemperatureRange_C[0],
                    kTemperatureRange_C[1]);
    }
  }
  return std::nullopt;
}

std::optional<std::string> ThermalProblem(const UnitRequest& r) {
  const char* with =
      !r.orientations.empty()                                            ? "{{orientations}}"
      : r.bias_model_auto || (r.bias_model && !r.bias_model->constant()) ? "{{bias_model}}"
      : !r.model                                                         ? "{{model}} auto"
      : r.method && *r.method != SolverMethod::kJoint                    ? "{{method}}"
      : r.frame && *r.frame != Frame::kXFirst                            ? "{{frame}}"
      : r.estimator && *r.estimator != Estimator::kMaximumLikelihood     ? "{{estimator}}"
      : !r.bias_random_walk.empty()                                      ? "{{bias_random_walk}}"
      : !r.noise.empty()                                                 ? "{{noise}}"
                                                                         : nullptr;
  if (with != nullptr) {
    return std::string(
               "{{thermal}} is the joint maximum-likelihood fit ({{method}} joint, {{estimator}} "
               "ml, {{frame}} x-first) of a model chosen by {{model}} linear or quadratic, with a "
               "bias constant in time: not with ") +
           with;
  }
  if (r.gyro && r.inputs.size() > 1) {
    return "{{thermal}} with {{gyro}} calibrates the gyroscope from one recording through the "
           "temperatures (a ramp, its turns between the positions): give one {{input}}";
  }
  if (!r.thermal_degrees && !r.cross_validate) {
    return "{{thermal}} auto decides on held-out error: it needs the cross-validation that "
           "{{no_crossval}} turns off";
  }
  return std::nullopt;
}

std::optional<std::string> KnownOrientationProblem(const UnitRequest& r) {
  const char* given = r.method                            ? "{{method}}"
                      : r.init                            ? "{{init}}"
                      : r.frame                           ? "{{frame}}"
                      : r.estimator                       ? "{{estimator}}"
                      : r.max_iterations != 0             ? "{{max_iterations}}"
                      : r.bias_model || r.bias_model_auto ? "{{bias_model}}"
                      : !r.bias_random_walk.empty()       ? "{{bias_random_walk}}"
                      : !r.noise.empty()                  ? "{{noise}}"
                                                          : nullptr;
  if (given != nullptr) {
    return std::string(given) +
           " does not apply with {{orientations}} (a closed-form fit in the platform frame)";
  }
  if (!r.model) {
    return "{{model}} auto is not available with {{orientations}}: give linear or quadratic";
  }
  return KnownOrientationOptionsOf(r).Validate();
}

std::optional<std::string> RandomWalkProblem(const UnitRequest& r) {
  const std::vector<double>& v = r.bias_random_walk;
  if (v.empty() && r.noise.empty()) return std::nullopt;
  const bool spline =
      r.bias_model_auto || (r.bias_model && r.bias_model->kind == BiasModelKind::kSpline);
  if (!spline) {
    return std::string(r.noise.empty() ? "{{bias_random_walk}}" : "{{noise}}") +
           " is the random-walk prior of a spline bias: give {{bias_model}} spline:K or auto "
           "with it, not " +
           BiasModelText(r);
  }
  if (!r.noise.empty()) return std::nullopt;  // its values are checked as it is read
  if (v.size() != 1 && v.size() != 3) {
    return "{{bias_random_walk}} takes one value or three (x,y,z), not " +
           std::to_string(v.size()) + " (the decimal point is '.')";
  }
  for (double q : v) {
    if (!(q >= kMinRandomWalk && q <= kMaxRandomWalk)) {
      return Format("{{bias_random_walk}} must be from %g to %g m/s^2/sqrt(s), not %g",
                    kMinRandomWalk, kMaxRandomWalk, q);
    }
  }
  return std::nullopt;
}

std::optional<std::string> ThermalDegreesProblem(const UnitRequest& r) {
  if (!r.thermal || !r.thermal_degrees) return std::nullopt;
  const ThermalDegrees& d = *r.thermal_degrees;
  try {
    (void)ThermalSlots(r.model.value_or(ModelKind::kLinear), d);
  } catch (const std::invalid_argument& e) {
    return std::string("{{thermal}}: ") + e.what();
  }
  if (d.Max() == 0) {
    return Format(
        "{{thermal}} %d,%d%s has no temperature term: leave {{thermal}} out for "
        "parameters constant over temperature",
        d.K, d.bias, d.k2 != 0 ? Format(",%d", d.k2).c_str() : "");
  }
  return std::nullopt;
}

// The rules of an orientation-free fit.
std::optional<std::string> FreeFitProblem(const UnitRequest& r) {
  const SolverMethod method = r.method.value_or(SolverMethod::kJoint);
  if (!OneOf(method, kOrientationFreeMethods)) {
    return NotOneOf("method", method, kOrientationFreeMethods);
  }
  if (r.gyro && !IsMaximumLikelihood(method)) {
    return "{{gyro}} and {{gyro_columns}} need a maximum-likelihood {{method}} (joint, two-step "
           "or newton-lagrange): the gyroscope's fit weighs the accelerometer by the residual of "
           "its fit, which " +
           std::string(NameOf(method)) + " does not estimate";
  }
  if (r.init && !OneOf(*r.init, kInitializations)) {
    return NotOneOf("init", *r.init, kInitializations);
  }
  if (r.frame == Frame::kPlatform) {
    return "{{frame}} platform is the frame of known orientations: give them with "
           "{{orientations}}";
  }
  if (auto why = RandomWalkProblem(r)) return why;
  const std::string bias = BiasModelText(r);
  if (bias != "constant" && r.gyro) {
    return "{{bias_model}} " + bias +
           " does not apply with the gyroscope: the joint fit with its rotations takes the "
           "accelerometer's bias as constant";
  }
  if (r.bias_model_auto && !r.cross_validate) {
    return "{{bias_model}} auto decides on held-out error: it needs the cross-validation that "
           "{{no_crossval}} turns off";
  }
  if (!r.model && !r.cross_validate) {
    return "{{model}} auto decides on held-out error: it needs the cross-validation that "
           "{{no_crossval}} turns off";
  }
  const CalibrationOptions options = CalibrationOptionsOf(r);
  if (auto why = options.Validate()) return why;
  if (r.bias_model_auto) {  // its candidates must be fittable as the options stand
    CalibrationOptions drifting = options;
    drifting.bias_model = BiasModel{BiasModelKind::kLinear, 0};
    if (auto why = drifting.Validate()) return "{{bias_model}} auto: " + *why;
  }
  if (!r.model) {
    CalibrationOptions quadratic = options;
    quadratic.model = ModelKind::kQuadratic;
    if (auto why = quadratic.Validate()) return "{{model}} auto: " + *why;
  }
  return ThermalDegreesProblem(r);
}

}  // namespace

std::string BiasModelText(const UnitRequest& r) {
  return r.bias_model_auto ? "auto" : r.bias_model ? ToString(*r.bias_model) : "constant";
}

GyroCalibrationOptions GyroOptionsOf(const UnitRequest& r) {
  GyroCalibrationOptions o;
  o.unit = r.gyro_units;
  o.estimator = GyroEstimatorOf(r);
  if (r.thermal) {
    o.thermal.emplace();
    o.thermal->degree = r.gyro_thermal;
  }
  o.model = r.gyro_model;
  o.validate = r.cross_validate;
  o.latitude_deg = r.latitude_deg;  // the Earth rate's vertical part, taken out
  return o;
}

GyroEstimator GyroEstimatorOf(const UnitRequest& r) {
  if (r.gyro_estimator) return *r.gyro_estimator;
  return !r.orientations.empty() || r.thermal ? GyroEstimator::kTwoStage : GyroEstimator::kJoint;
}

CalibrationOptions CalibrationOptionsOf(const UnitRequest& r) {
  CalibrationOptions o;
  o.model = r.model.value_or(ModelKind::kLinear);
  o.method = r.method.value_or(SolverMethod::kJoint);
  o.initialization = r.init.value_or(Initialization::kAuto);
  o.frame = r.frame.value_or(Frame::kXFirst);
  o.estimator = r.estimator.value_or(Estimator::kMaximumLikelihood);
  if (r.bias_model) o.bias_model = *r.bias_model;
  o.outliers = r.outliers;
  o.cross_validate = r.cross_validate;
  o.gravity = r.GravityInUnit();
  if (r.max_iterations > 0) {
    o.two_step.max_sweeps = r.max_iterations;
    o.joint.max_iterations = r.max_iterations;
    o.modulus.max_iterations = r.max_iterations;
    o.newton_lagrange.max_iterations = r.max_iterations;
  }
  return o;
}

KnownOrientationOptions KnownOrientationOptionsOf(const UnitRequest& r) {
  KnownOrientationOptions o;
  o.model = r.model.value_or(ModelKind::kLinear);
  o.cross_validate = r.cross_validate;
  o.outliers = r.outliers;
  o.gravity = r.GravityInUnit();
  return o;
}

std::optional<std::string> GyroInputProblem(const std::string& accel_path,
                                            const std::vector<std::string>& accel_columns,
                                            const SensorInput& gyro) {
  const std::vector<std::string>& columns = gyro.columns;
  if (!columns.empty() && columns.size() != 3 && columns.size() != 4) {
    return "{{gyro_columns}} takes x,y,z or time,x,y,z";
  }
  if (gyro.log.empty() && columns.empty()) {
    return "the gyroscope's rates: give {{gyro}} LOG or {{gyro_columns}}";
  }
  if (gyro.log.empty() && accel_path == "-") {
    return "{{gyro_columns}} reads the log a second time: it cannot be standard input";
  }
  if (gyro.log == "-" && accel_path == "-") {
    return "the accelerometer's log and {{gyro}} are both standard input, which can be read "
           "once: give one of them as a file";
  }
  if (gyro.log.empty() && accel_columns.size() >= 3 && columns.size() >= 3 &&
      std::equal(columns.end() - 3, columns.end(), accel_columns.end() - 3)) {
    return "{{gyro_columns}} names the accelerometer's columns ({{columns}}): give the rates' "
           "own";
  }
  for (std::size_t a = 0; a < columns.size(); ++a) {
    for (std::size_t b = 0; b < a; ++b) {
      if (columns[a] == columns[b]) {
        return "{{gyro_columns}} names '" + columns[a] +
               "' twice: each rate axis needs its own column";
      }
    }
  }
  return std::nullopt;
}

namespace {

std::optional<std::string> OptionsProblem(const UnitRequest& r) {
  if (r.inputs.empty()) return std::string("no {{input}}: give the accelerometer's log");
  if (r.max_iterations < 0) {
    return Format("{{max_iterations}} must be at least 1 (or 0, each solver's own), not %d",
                  r.max_iterations);
  }
  if (!r.provenance.date.empty()) {
    if (const auto why = CheckProvenanceDate(r.provenance.date)) return "{{date}}: " + *why;
  }
  if (r.gyro) {
    if (auto why = GyroProblem(r)) return why;
  }
  if (auto why = TemperaturesProblem(r)) return why;
  if (r.thermal) {
    if (auto why = ThermalProblem(r)) return why;
  } else if (r.thermal_degrees) {
    return std::string("{{thermal}} degrees are given without {{thermal}}");
  }
  if (!r.orientations.empty()) return KnownOrientationProblem(r);
  return FreeFitProblem(r);
}

}  // namespace

double UnitRequest::GravityInUnit() const {
  return units == ForceUnit::kMetersPerSecond2 ? gravity_ms2 : gravity_ms2 / kStandardGravity_ms2;
}

std::optional<std::string> UnitRequest::Validate() const {
  if (auto why = OptionsProblem(*this)) return why;
  return load.detection.Validate();
}

}  // namespace accelcal
