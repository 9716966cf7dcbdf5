// A calibration's named quantities and its verdict against a production line's limits
// (acceptance.hpp). The limits file is read in limits_file.cpp.
#include "accelcal/acceptance.hpp"

#include <algorithm>
#include <cmath>

#include "accelcal/engineering.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/gyro_model.hpp"
#include "accelcal/model.hpp"
#include "accelcal/sensor_parameters.hpp"
#include "core/text_format.hpp"

namespace accelcal {
namespace {

const char* const kAxes[] = {"x", "y", "z"};

// 1σ of flat parameter `i` from a covariance in the slots' order, when the file has it.
std::optional<double> SigmaOf(const Eigen::MatrixXd& covariance, int i, int n) {
  if (covariance.rows() != n || covariance.cols() != n) return std::nullopt;
  return std::sqrt(std::max(0.0, covariance(i, i)));
}

// A sensor's model parameters (sensor_parameters.hpp), each with its 1σ and unit.
void ParameterQuantities(const std::string& sensor, const std::vector<SensorParameter>& list,
                         const Eigen::MatrixXd& covariance, const std::string& raw,
                         const std::string& quantity, const std::string& other,
                         std::vector<CalibrationQuantity>* out) {
  const int n = static_cast<int>(list.size());
  for (int i = 0; i < n; ++i) {
    const SensorParameter& p = list[static_cast<std::size_t>(i)];
    out->push_back({sensor + "." + std::string(p.name), p.value, SigmaOf(covariance, i, n),
                    ParameterUnit(p.role, raw, quantity, other)});
  }
}

void AccelerometerQuantities(const LoadedCalibration& cal, std::vector<CalibrationQuantity>* out) {
  const auto add = [&](const std::string& name, double value, std::optional<double> sigma,
                       std::string unit) {
    out->push_back({"accelerometer." + name, value, sigma, std::move(unit)});
  };
  const std::string raw(cal.raw_unit), force(ToString(cal.unit));
  const int n = static_cast<int>(ParameterSlots(cal.model, cal.frame).size());
  ParameterQuantities("accelerometer", ListParameters(cal.params, cal.model, cal.frame),
                      cal.covariance, raw, force, "", out);
  if (cal.model == ModelKind::kLinear) {  // k2 = 0 by the model: a value, not an estimate
    for (int a = 0; a < 3; ++a) {
      add(std::string("k2_") + kAxes[a], 0.0, std::nullopt, raw + " per (" + force + ")^2");
      out->back().fixed = true;
    }
  }
  // Engineering quantities (paper 000 Table 3), their 1σ propagated from the covariance.
  const EngineeringParameters eng = ToEngineering(cal.params, cal.gravity);
  std::optional<EngineeringStd> std;
  if (cal.covariance.rows() == n && cal.covariance.cols() == n) {
    std = EngineeringUncertainty(cal.params, cal.model, cal.frame, cal.gravity, cal.covariance);
  }
  const auto opt = [&](auto member) -> std::optional<double> {
    return std ? std::optional<double>(member(*std)) : std::nullopt;
  };
  for (int a = 0; a < 3; ++a) {
    add(std::string("scale_factor_") + kAxes[a], eng.scale_factor(a),
        opt([a](const EngineeringStd& e) { return e.scale_factor(a); }), raw + " per " + force);
  }
  const Misalignment mis = MisalignmentOf(cal.params.K, cal.frame);
  for (int i = 0; i < mis.rad.size(); ++i) {
    add("misalignment_" + std::string(mis.names[i]), mis.rad(i),
        opt([i](const EngineeringStd& e) { return e.misalignment_rad(i); }), "rad");
  }
  for (int a = 0; a < 3; ++a) {
    add(std::string("bias_specific_force_") + kAxes[a], eng.bias_force(a),
        opt([a](const EngineeringStd& e) { return e.bias_force(a); }), force);
  }
  for (int a = 0; a < 3; ++a) {
    add(std::string("k2_g_per_g2_") + kAxes[a], eng.k2_g_per_g2(a),
        cal.model == ModelKind::kQuadratic
            ? opt([a](const EngineeringStd& e) { return e.k2_g_per_g2(a); })
            : std::nullopt,
        "g/g^2");
    out->back().fixed = cal.model == ModelKind::kLinear;
  }
  if (cal.gravity_norm_rms_after) add("rms_after", *cal.gravity_norm_rms_after, {}, force);
  if (cal.crossval_rms) add("heldout_rms", *cal.crossval_rms, {}, force);
  if (cal.noise_sigma_raw) add("noise_sigma_raw", *cal.noise_sigma_raw, {}, raw);
  if (!cal.positions.empty()) {
    const auto excluded = std::count_if(cal.positions.begin(), cal.positions.end(),
                                        [](const FilePosition& p) { return p.excluded; });
    add("positions", static_cast<double>(cal.positions.size() - excluded), {}, "");
    add("excluded_positions", static_cast<double>(excluded), {}, "");
  }
}

void GyroscopeQuantities(const UnitGyroscope& gyro, std::vector<CalibrationQuantity>* out) {
  const auto add = [&](const std::string& name, double value, std::optional<double> sigma,
                       std::string unit) {
    out->push_back({"gyroscope." + name, value, sigma, std::move(unit)});
  };
  const std::string& raw = gyro.raw_unit;
  ParameterQuantities("gyroscope", ListParameters(gyro.params, gyro.model), gyro.covariance, raw,
                      "rad/s", "specific force", out);
  for (int a = 0; a < 3; ++a) {
    add(std::string("scale_factor_") + kAxes[a], gyro.params.K.row(a).norm(), {},
        raw + " per rad/s");
  }
  if (std::isfinite(gyro.rms_deg)) add("rms_deg", gyro.rms_deg, {}, "deg");
  if (std::isfinite(gyro.heldout_rms_deg)) add("heldout_rms_deg", gyro.heldout_rms_deg, {}, "deg");
}

std::string Number(double v) { return internal::Format("%.6g", v); }

bool CanHaveSigma(const std::string& name) {
  for (const QuantityName& q : KnownQuantityNames()) {
    if (q.name == name) return q.has_sigma;
  }
  return false;
}

}  // namespace

std::vector<CalibrationQuantity> CalibrationQuantities(const LoadedCalibration& cal) {
  std::vector<CalibrationQuantity> out;
  AccelerometerQuantities(cal, &out);
  if (cal.gyroscope) GyroscopeQuantities(*cal.gyroscope, &out);
  return out;
}

const std::vector<QuantityName>& KnownQuantityNames() {
  // The quantities of calibrations of every model and frame, with a gyroscope of each model and
  // every statistic recorded: CalibrationQuantities itself says what it can name.
  static const std::vector<QuantityName> names = [] {
    std::vector<QuantityName> all;
    const auto take = [&](const LoadedCalibration& cal) {
      for (const CalibrationQuantity& q : CalibrationQuantities(cal)) {
        const auto at = std::find_if(all.begin(), all.end(),
                                     [&](const QuantityName& k) { return k.name == q.name; });
        if (at == all.end()) {
          all.push_back({q.name, q.sigma.has_value()});
        } else {
          at->has_sigma = at->has_sigma || q.sigma.has_value();  // k2: in the quadratic model
        }
      }
    };
    for (ModelKind model : {ModelKind::kLinear, ModelKind::kQuadratic}) {
      for (Frame frame : {Frame::kXFirst, Frame::kZFirst, Frame::kPlatform}) {
        for (GyroModelKind gyro_model : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
          LoadedCalibration cal;
          cal.model = model;
          cal.frame = frame;
          cal.gravity = 9.80665;
          const int n = static_cast<int>(ParameterSlots(model, frame).size());
          cal.covariance = Eigen::MatrixXd::Identity(n, n) * 1e-6;
          cal.gravity_norm_rms_after = cal.crossval_rms = cal.noise_sigma_raw = 0.0;
          cal.positions.resize(1);
          UnitGyroscope gyro;
          gyro.model = gyro_model;
          const int m = NumGyroParameters(gyro_model);
          gyro.covariance = Eigen::MatrixXd::Identity(m, m);
          gyro.rms_deg = gyro.heldout_rms_deg = 0.0;
          cal.gyroscope = gyro;
          take(cal);
        }
      }
    }
    return all;
  }();
  return names;
}

bool QuantityMatches(std::string_view pattern, std::string_view name) {
  // Iterative glob with '*' only: on a mismatch after a star, the star takes one more character.
  std::size_t p = 0, n = 0, star = std::string_view::npos, resume = 0;
  while (n < name.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = n;
    } else if (p < pattern.size() && pattern[p] == name[n]) {
      ++p;
      ++n;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      n = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

Acceptance Accept(const LoadedCalibration& cal, const AcceptanceLimits& limits) {
  Acceptance result;
  const auto fail = [&](std::string quantity, std::optional<double> value, std::string text,
                        std::size_t line) {
    result.failures.push_back({std::move(quantity), value, std::move(text), line});
  };
  // Limits written in another unit than the calibration's are not compared at all.
  if (cal.unit != limits.specific_force_unit) {
    fail("units", std::nullopt,
         internal::Format("the calibration's specific force is in %s, the limits' in %s",
                          std::string(ToString(cal.unit)).c_str(),
                          std::string(ToString(limits.specific_force_unit)).c_str()),
         0);
  } else if (!limits.raw_unit.empty() && cal.raw_unit != limits.raw_unit) {
    fail("units", std::nullopt,
         "the calibration's raw unit is '" + cal.raw_unit + "', the limits' '" + limits.raw_unit +
             "'",
         0);
  } else {
    const std::vector<CalibrationQuantity> quantities = CalibrationQuantities(cal);
    for (const Limit& limit : limits.limits) {
      const bool sigma = limit.statistic == LimitStatistic::kSigma;
      const std::string suffix = sigma ? ".sigma" : "";
      bool named = false;
      for (const CalibrationQuantity& q : quantities) {
        if (!QuantityMatches(limit.pattern, q.name)) continue;
        // A σ pattern such as accelerometer.*.sigma names the quantities that have one (in
        // this model: k2 of the linear model is 0 by it).
        const bool wildcard = limit.pattern.find('*') != std::string::npos;
        if (sigma && (!CanHaveSigma(q.name) || (q.fixed && wildcard))) continue;
        named = true;
        const std::string name = q.name + suffix;
        if (sigma && q.fixed) {
          fail(name, std::nullopt, name + ": fixed by the calibration's model, not estimated",
               limit.line);
          continue;
        }
        if (sigma && !q.sigma) {
          fail(name, std::nullopt, name + ": the calibration has no covariance to give it",
               limit.line);
          continue;
        }
        const double x = sigma ? *q.sigma : q.value;
        ++result.checked;
        const std::string is = name + " = " + Number(x);
        if (limit.min && !(x >= *limit.min)) {
          fail(name, x, is + " is below min " + Number(*limit.min), limit.line);
        } else if (limit.max && !(x <= *limit.max)) {
          fail(name, x, is + " is above max " + Number(*limit.max), limit.line);
        } else if (limit.abs_max && !(std::abs(x) <= *limit.abs_max)) {
          fail(name, x, is + " exceeds abs_max " + Number(*limit.abs_max), limit.line);
        }
      }
      if (!named) {
        fail(limit.pattern + suffix, std::nullopt,
             limit.pattern + suffix + ": not in this calibration", limit.line);
      }
    }
  }
  if (limits.max_severity) {
    for (const Finding& f : cal.diagnostics.value_or(std::vector<Finding>())) {
      if (f.severity <= *limits.max_severity) continue;
      fail("diagnosis", std::nullopt,
           "diagnosis: " + std::string(ToString(f.severity)) + " " + f.code + " (above " +
               std::string(ToString(*limits.max_severity)) + ")",
           0);
    }
  }
  if (cal.verdict == "failed") {
    fail("verdict", std::nullopt, "the calibration failed its own checks (verdict failed)", 0);
  }
  result.passed = result.failures.empty();
  return result;
}

}  // namespace accelcal
