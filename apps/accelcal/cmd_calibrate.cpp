// accelcal calibrate: the summary, the warnings, the calibration file and report.
#include "commands.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "accelcal/engineering.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/known_orientation.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/noise_file.hpp"
#include "accelcal/orientation_file.hpp"
#include "accelcal/position_noise.hpp"
#include "accelcal/report.hpp"
#include "accelcal/thermal_calibration.hpp"
#include "cli_common.hpp"
#include "output.hpp"

namespace accelcal::cli {
namespace {

// The label of the gyroscope's raw unit: its declared unit (rad/s, deg/s), or for raw counts the
// accelerometer's raw label when that is a label of counts ("counts", "LSB"), else "raw": an
// accelerometer read in m/s2 or g says nothing of the gyroscope's unit.

void PrintInput(const LoadedInput& in) {
  for (const LoadedFile& f : in.files) {
    if (f.data.kind == InputKind::kPositions) {
      Say("input     %s: %zu positions (%s)\n", f.path.c_str(), f.data.positions.size(),
          WithReaderFlags(f.data.kind_reason).c_str());
      continue;
    }
    const StaticDetectionResult& d = *f.detection;
    Say("input     %s: raw log, %zu samples at %.6g Hz (%s)\n", f.path.c_str(),
        f.data.raw.samples.size(), d.rate_hz, WithReaderFlags(f.data.kind_reason).c_str());
    Say("detection %zu static intervals (window %zu samples, threshold %.4g raw^2 = %.3g x "
        "noise reference)\n",
        d.intervals.size(), d.window_samples, d.threshold,
        d.noise_reference > 0 ? d.threshold / d.noise_reference : 0.0);
  }
  if (in.files.size() > 1) {
    Say("pooled    %zu positions from %zu files\n", in.positions.size(), in.files.size());
  }
}

// The three parameter pairs with the largest |correlation|: what the positions cannot separate.
void PrintStrongestCorrelations(const Eigen::MatrixXd& covariance,
                                const std::vector<ParameterSlot>& slots) {
  struct Pair {
    double rho;
    Eigen::Index i, j;
  };
  std::vector<Pair> pairs;
  for (Eigen::Index i = 0; i < covariance.rows(); ++i) {
    for (Eigen::Index j = 0; j < i; ++j) {
      const double rho = covariance(i, j) / std::sqrt(covariance(i, i) * covariance(j, j));
      if (std::isfinite(rho)) pairs.push_back({rho, i, j});
    }
  }
  const std::size_t shown = std::min<std::size_t>(3, pairs.size());
  std::partial_sort(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(shown), pairs.end(),
                    [](const Pair& a, const Pair& b) { return std::abs(a.rho) > std::abs(b.rho); });
  Say("  strongest correlations:");
  for (std::size_t k = 0; k < shown; ++k) {
    Say("%s %s/%s %+.3f", k ? "," : "",
        std::string(slots[static_cast<std::size_t>(pairs[k].i)].name).c_str(),
        std::string(slots[static_cast<std::size_t>(pairs[k].j)].name).c_str(), pairs[k].rho);
  }
  Say("\n");
}

// The fitted bias drift (bias_drift.hpp): its basis and D ± 1σ per axis.
void PrintDrift(const BiasDrift& drift, ModelKind model, const std::string& raw_unit) {
  const BiasTimeBasis& basis = drift.basis;
  const Eigen::Index J = drift.D.cols();
  const Eigen::Index P = NumParameters(model);
  const bool have_std = drift.covariance.rows() == P + 3 * J;
  if (basis.model.kind == BiasModelKind::kLinear) {
    Say("\nbias drift linear: b(t) = b + D (t - t_ref), t_ref %.6g s (the positions' mean time), D "
        "in %s per minute%s\n",
        basis.t_ref_s, raw_unit.c_str(), have_std ? " +- 1 sigma" : "");
  } else {
    std::string knots;
    for (double t : basis.knots_s) knots += Format(" %.6g", t);
    Say("\nbias drift %s: b(t) linear between knots at%s s, held outside; t_ref %.6g s (the "
        "positions' mean time); D_j = bias at knot j less bias at the first knot, in %s%s\n",
        ToString(basis.model).c_str(), knots.c_str(), basis.t_ref_s, raw_unit.c_str(),
        have_std ? " +- 1 sigma" : "");
  }
  const char* axes = "xyz";
  for (int i = 0; i < 3; ++i) {
    std::string row;
    for (Eigen::Index j = 0; j < J; ++j) {
      const Eigen::Index index = P + i * J + j;
      row += Format(" %14.6g", drift.D(i, j));
      if (have_std) row += Format(" +- %-9.2g", std::sqrt(drift.covariance(index, index)));
    }
    Say("  D_%c %s\n", axes[i], row.c_str());
  }
}

void PrintCalibration(const CalibrationResult& r, const std::vector<Position>& positions,
                      const std::vector<std::string>& position_file, const Gravity& g,
                      const std::string& raw_unit) {
  const char* u = g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g";
  const bool have_std = r.covariance.size() > 0;
  const auto& slots = ParameterSlots(r.model, r.frame);
  Say("\nmodel     %s, p = K f + b + k2 * f^2, frame %s, gravity %.9g %s (%s)\n",
      std::string(ToString(r.model)).c_str(), std::string(ToString(r.frame)).c_str(), g.in_unit, u,
      g.origin.c_str());
  const std::string noise =
      r.noise_source == "samples"
          ? Format("noise of the positions' means, x %.3g scatter ratio", r.scatter_ratio)
      : r.noise_source == "joint"
          ? std::string(
                "joint fit with the gyroscope's rotations, each group's noise from its "
                "scatter")
          : std::string("noise from the residuals");
  Say("\nparameters (K in %s per %s, b in %s, k2 in %s per %s^2; +- 1 sigma, %s)\n",
      raw_unit.c_str(), u, raw_unit.c_str(), raw_unit.c_str(), u, noise.c_str());
  const Eigen::VectorXd theta = Pack(r.params, slots);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const auto idx = static_cast<Eigen::Index>(i);
    if (have_std) {
      Say("  %-5s %18.10g +- %.3g\n", std::string(slots[i].name).c_str(), theta(idx),
          std::sqrt(r.covariance(idx, idx)));
    } else {
      Say("  %-5s %18.10g\n", std::string(slots[i].name).c_str(), theta(idx));
    }
  }
  if (have_std) PrintStrongestCorrelations(r.covariance, slots);
  const EngineeringParameters e = ToEngineering(r.params, r.gravity);
  const double ug = 1e6 / r.gravity;
  // ±1σ propagated from the parameter covariance, when there is one.
  std::optional<EngineeringStd> sd;
  if (have_std) {
    sd = EngineeringUncertainty(r.params, r.model, r.frame, r.gravity, r.covariance);
  }
  // Values ± their 1σ (`sigma` empty: none).
  const auto pm = [&](const Eigen::VectorXd& v, const Eigen::VectorXd& sigma, double scale,
                      const char* format) {
    std::string text;
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      text += Format(format, v(i) * scale);
      if (sigma.size() > 0) text += Format(" +- %.2g", sigma(i) * scale);
      text += i + 1 < v.size() ? "   " : "";
    }
    return text;
  };
  const auto sd_of = [&](auto member) {
    return sd ? Eigen::VectorXd(*sd.*member) : Eigen::VectorXd();
  };
  Say("\nengineering (%s conventions%s)\n",
      r.frame == Frame::kPlatform ? "paper 003 eq. (5)" : "paper 000 Table 3",
      sd ? "; +- 1 sigma propagated from the parameters" : "");
  Say("  scale factor     %s  %s/%s\n",
      pm(e.scale_factor, sd_of(&EngineeringStd::scale_factor), 1.0, "%.10g").c_str(),
      raw_unit.c_str(), u);
  const Misalignment tau = MisalignmentOf(r.params.K, r.frame);
  std::string names;
  for (std::string_view name : tau.names) names += (names.empty() ? "" : ", ") + std::string(name);
  Say("  misalignment     %s\n", names.c_str());
  Say("                   %s  arcsec\n",
      pm(tau.rad, sd_of(&EngineeringStd::misalignment_rad), kArcsecPerRad, "%.4f").c_str());
  Say("  bias             %s  %s\n",
      pm(e.bias_force, sd_of(&EngineeringStd::bias_force), 1.0, "%.6g").c_str(), u);
  Say("                   %s  ug\n",
      pm(e.bias_force, sd_of(&EngineeringStd::bias_force), ug, "%.6g").c_str());
  if (r.model == ModelKind::kQuadratic) {
    Say("  squared coeff.   %s  g/g^2\n",
        pm(e.k2_g_per_g2, sd_of(&EngineeringStd::k2_g_per_g2), 1.0, "%.4g").c_str());
  }
  if (r.drift) PrintDrift(*r.drift, r.model, raw_unit);
  const std::vector<Vec3> means = Means(positions);
  const std::vector<double> errors = GravityNormErrors(r, means);
  Say("\npositions (|f|-g in %s, residual p - mu in %s)\n", u, raw_unit.c_str());
  Say("  %3s %8s %42s %12s %36s\n", "#", "samples", "mean", "|f|-g", "residual");
  for (std::size_t k = 0; k < positions.size(); ++k) {
    Say("  %3zu %8zu %s %12.4g %s%s\n", k + 1, positions[k].samples, Vec(positions[k].mean).c_str(),
        errors[k], Vec(r.residuals[k], "%12.4g").c_str(), r.excluded(k) ? "  excluded" : "");
  }
  for (const OutlierFinding& o : r.outliers) {
    Say("%s  %s\n", o.excluded ? "excluded " : "flagged  ",
        OutlierMessage(o, positions, errors, u, position_file).c_str());
  }
  if (!r.outlier_note.empty()) Say("screening %s\n", r.outlier_note.c_str());
  const std::optional<double> before = GravityNormRmsUncalibrated(means, r.gravity);
  const std::vector<double> used_errors = r.InFit(errors);  // outliers excluded
  Say("\nrms |f|-g  before: %s   after: %.6g %s%s\n",
      before ? Format("%.6g %s", *before, u).c_str()
             : Format("n/a (raw readings are not in %s)", u).c_str(),
      Rms(used_errors), u, used_errors.size() < errors.size() ? " (positions in the fit)" : "");
  if (r.crossval_rms) {
    Say("held-out  rms |f|-g %.6g %s (each position corrected by a fit without it)\n",
        *r.crossval_rms, u);
  } else if (!r.crossval_note.empty()) {
    Say("held-out  n/a: %s\n", r.crossval_note.c_str());
  }
  Say("solver    %s\n", r.summary.BriefReport().c_str());
  if (!r.summary.initialization_note.empty()) {
    Say("note      %s\n", r.summary.initialization_note.c_str());
  }
}

void PrintModelSelection(const ModelSelection& s, bool requested_auto) {
  if (requested_auto) {
    Say("model     auto -> %s: %s\n", std::string(ToString(s.chosen)).c_str(), s.reason.c_str());
  } else {
    Say("model     quadratic (requested); the data support %s: %s\n",
        std::string(ToString(s.chosen)).c_str(), s.reason.c_str());
  }
  if (s.quadratic && std::isfinite(s.k2_t.sum())) {
    Say("          squared coefficients k2/sigma: %.3g %.3g %.3g (significant beyond %.3g)\n",
        s.k2_t(0), s.k2_t(1), s.k2_t(2), s.k2_t_threshold);
  }
}

// What the command line adds to a finding: the option that acts on it.
const char* OptionHint(const Finding& f) {
  if (f.code == "units") {
    return f.message.find("calibrate in g") != std::string::npos ? " (--units g)"
                                                                 : " (--units m/s2)";
  }
  if (f.code == "outlier_limit") return " (--max-outliers)";
  if (f.code == "drifting_rest" && f.severity == Severity::kWarning) {
    return " (--bias-model auto fits a bias that follows time)";
  }
  if (f.code == "time_unit") return " (--time-unit)";
  if (f.code == "positions_like_samples") return " (--input-kind raw)";
  return "";
}

// Warnings and failures on stderr (outliers and still periods not used are told where found),
// each under the file it is about: the gyroscope's under its log.
void PrintFindings(const Diagnosis& diagnosis, const std::string& input_path,
                   const std::string& gyro_path) {
  for (const Finding& f : diagnosis.findings) {
    if (f.code == "outlier" || f.code == "rejected_period") continue;
    const std::string& path = f.code.rfind("gyro_", 0) == 0 ? gyro_path : input_path;
    if (f.severity == Severity::kFailure) {
      WriteErr(Format("accelcal: %s: failed check (%s): %s%s\n", path.c_str(), f.code.c_str(),
                      f.message.c_str(), OptionHint(f)));
    } else if (f.severity == Severity::kWarning) {
      Warn("%s: %s%s\n", path.c_str(), f.message.c_str(), OptionHint(f));
    }
  }
}

// The gyroscope read and calibrated beside the accelerometer (calibrate --gyro / --gyro-columns).
struct GyroRun {
  std::string path;
  InputData data;
  GyroCalibration calibration;
};

// The gyroscope's raw-unit label: --gyro-units when its rates were in a unit, else the unit its
// binary-log stream has by its specification (PX4's sensor_gyro, a ROS Imu's angular_velocity:
// rad/s), else --raw-units unless that names a force unit.
std::string GyroRawLabel(const GyroRun& gyro, const CalibrateArgs& args) {
  if (gyro.calibration.unit != GyroUnit::kRaw) return args.gyro_units;
  if (gyro.data.stream && !gyro.data.stream->unit.empty()) return gyro.data.stream->unit;
  return ForceUnitFromString(args.raw_units) ? std::string("raw") : args.raw_units;
}

bool GyroWanted(const CalibrateArgs& args) {
  return !args.gyro.empty() || !args.gyro_columns.empty();
}

GyroCalibrationOptions GyroOptions(const CalibrateArgs& args) {
  GyroCalibrationOptions o;
  o.unit = ParseChoice<GyroUnit>(args.gyro_units, "--gyro-units");
  const bool known = !args.orientations.empty();
  const bool thermal = !args.thermal.empty();
  o.estimator = args.gyro_estimator.empty()
                    ? (known || thermal ? GyroEstimator::kTwoStage : GyroEstimator::kJoint)
                    : ParseChoice<GyroEstimator>(args.gyro_estimator, "--gyro-estimator");
  if (known && o.estimator == GyroEstimator::kJoint) {
    throw UsageError(
        "--gyro-estimator joint fits every position's gravity direction, which --orientations "
        "gives: the gyroscope is fitted on top of the known-orientation calibration "
        "(two-stage)");
  }
  if (thermal && o.estimator == GyroEstimator::kJoint) {
    throw UsageError(
        "--gyro-estimator joint refits the accelerometer's parameters as constants, which "
        "--thermal's are not: the gyroscope is fitted on top of the calibration over "
        "temperature (two-stage, the default with --thermal)");
  }
  if (!args.gyro_thermal.empty() && !thermal) {
    throw UsageError(
        "--gyro-thermal is the gyroscope's offsets over temperature, fitted with --thermal: give "
        "it too");
  }
  if (thermal) {
    o.thermal.emplace();  // T_ref is the accelerometer's, set when it is fitted
    if (!args.gyro_thermal.empty() && args.gyro_thermal != "auto") {
      const std::string& d = args.gyro_thermal;
      if (d.size() != 1 || d[0] < '0' || d[0] > '0' + kMaxThermalDegree) {
        throw UsageError("--gyro-thermal: '" + d + "' is neither auto nor a degree from 0 to " +
                         std::to_string(kMaxThermalDegree));
      }
      o.thermal->degree = d[0] - '0';
    } else if (!args.cross_validate) {
      throw UsageError(
          "--gyro-thermal auto (the default with --thermal) decides on held-out error: it needs "
          "the cross-validation that --no-crossval turns off; give --gyro-thermal 0 to 3");
    }
  }
  if (args.gyro_model != "auto") {
    o.model = ParseEnum(GyroModelKindFromString(args.gyro_model), args.gyro_model, "--gyro-model",
                        (NameList<GyroModelKind>() + ", auto").c_str());
  } else if (!args.cross_validate && o.estimator != GyroEstimator::kImuTk) {
    throw UsageError(
        "the gyro's model is chosen on held-out rotations (--gyro-model auto, the default), "
        "which --no-crossval turns off: give --gyro-model linear or g-sensitive");
  }
  if (o.estimator == GyroEstimator::kImuTk && o.model && *o.model != GyroModelKind::kLinear) {
    throw UsageError(
        "--gyro-estimator imutk is imu_tk's method, which has no g-sensitivity: "
        "--gyro-model linear");
  }
  o.validate = args.cross_validate;
  o.latitude_deg = args.gravity.latitude_deg;  // the Earth rate's vertical part, taken out
  return o;
}

// The gyroscope's log, when it is a regular file of its own, read on a thread of its own while
// the accelerometer's is loaded and fitted: the same data, and what reading it throws is thrown
// where it was read before, after the accelerometer's fit (whose errors come first). Standard
// input, a FIFO or a device is read in turn as before: two readers must not share one.
class GyroLogAhead {
 public:
  explicit GyroLogAhead(const CalibrateArgs& args) {
    std::error_code error;
    if (!args.gyro.empty() && args.gyro != "-" && args.gyro != args.input.path &&
        std::filesystem::is_regular_file(args.gyro, error)) {
      pending_ = std::async(std::launch::async | std::launch::deferred, [&args] {
        return ReadGyroLog(args.input, args.gyro, args.gyro_columns, true);
      });
    }
  }
  // The log, read ahead or now.
  InputData Take(const CalibrateArgs& args) {
    if (pending_.valid()) return pending_.get();
    return ReadGyroLog(args.input, args.gyro, args.gyro_columns, true);
  }

 private:
  std::future<InputData> pending_;
};

GyroRun RunGyro(const CalibrateArgs& args, const LoadedInput& in, const CalibrationResult& accel,
                GyroLogAhead* ahead = nullptr) {
  GyroCalibrationOptions options = GyroOptions(args);
  if (options.thermal && accel.thermal) options.thermal->t_ref_c = accel.thermal->params.t_ref_c;
  const RawLog& accel_log = TheRawLogForGyro(in);
  GyroRun run;
  run.path = args.gyro.empty() ? args.input.path : args.gyro;
  run.data = ahead != nullptr ? ahead->Take(args)
                              : ReadGyroLog(args.input, args.gyro, args.gyro_columns, true);
  const std::string subject = DataSubject();
  DataSubject() = run.path;  // what CalibrateGyro refuses is the gyroscope's
  run.calibration = CalibrateGyro(accel_log, run.data.raw, in.positions, accel, options);
  DataSubject() = subject;
  return run;
}

void PrintGyro(const GyroRun& run, const std::string& raw_unit, const char* force_unit) {
  const GyroCalibration& g = run.calibration;
  const auto& slots = GyroParameterSlots(g.model);
  const bool have_std = g.covariance.size() > 0;
  Say("\ngyroscope %s: %zu samples; model %s (%s), %s fit, w_raw = K w + b + G f\n",
      run.path.c_str(), run.data.raw.samples.size(), std::string(ToString(g.model)).c_str(),
      g.model_reason.c_str(), std::string(ToString(g.estimator)).c_str());
  Say("parameters (K in %s per rad/s, b in %s, G in %s per %s; +- 1 sigma)\n", raw_unit.c_str(),
      raw_unit.c_str(), raw_unit.c_str(), force_unit);
  const Eigen::VectorXd theta = Pack(g.params, g.model);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const auto idx = static_cast<Eigen::Index>(i);
    if (have_std) {
      Say("  %-6s %18.10g +- %.3g\n", std::string(slots[i].name).c_str(), theta(idx),
          std::sqrt(g.covariance(idx, idx)));
    } else {
      Say("  %-6s %18.10g\n", std::string(slots[i].name).c_str(), theta(idx));
    }
  }
  Say("  scale factor (row norms of K)  %.8g  %.8g  %.8g  %s per rad/s\n", g.params.K.row(0).norm(),
      g.params.K.row(1).norm(), g.params.K.row(2).norm(), raw_unit.c_str());
  if (g.latitude_deg) {
    constexpr double kRadSToDegH = 180 / 3.14159265358979323846 * 3600;
    Say("  Earth rate at latitude %.6g deg: its vertical part %.4g deg/h taken out of the still "
        "rates; its horizontal part %.4g deg/h, in a heading the recording does not know, "
        "stays: the bias is not known better than that\n",
        *g.latitude_deg, g.earth_rate_vertical_rad_s * kRadSToDegH,
        g.earth_rate_horizontal_rad_s * kRadSToDegH);
  }
  Say("  rate noise  %.4g  %.4g  %.4g  %s per sample; scatter ratios: stills %.3g, rotations "
      "%.3g%s\n",
      g.noise_sigma_raw(0), g.noise_sigma_raw(1), g.noise_sigma_raw(2), raw_unit.c_str(),
      g.still_scatter_ratio, g.rotation_scatter_ratio,
      g.accelerometer ? Format(", accelerometer %.3g", g.accel_scatter_ratio).c_str() : "");
  if (const std::optional<GyroThermal>& t = g.thermal) {
    Say("  offsets over temperature  b(T) = b + sum_d b_d (T - T_ref)^d, T_ref %.6g degC, "
        "positions at %.4g to %.4g degC (%s): degree %d (%s)\n",
        t->bias.t_ref_c, t->range_c.first, t->range_c.second,
        internal::VisibleLine(t->temperature_source).c_str(), t->bias.degree(), t->reason.c_str());
    for (int d = 1; d <= t->bias.degree(); ++d) {
      const Vec3& b = t->bias.coefficients[static_cast<std::size_t>(d - 1)];
      std::string line = Format("    b_%d ", d);
      for (int a = 0; a < 3; ++a) {
        const auto i = static_cast<Eigen::Index>(3 * (d - 1) + a);
        line += Format(" %c %.6g +- %.2g", "xyz"[a], b(a), std::sqrt(t->bias.covariance(i, i)));
      }
      Say("%s  %s per K^%d\n", line.c_str(), raw_unit.c_str(), d);
    }
    Say("    the still rates' scatter about it %.3g times their noise; the rest of the gyroscope's "
        "calibration is at T_ref, from the rates with these offsets taken out\n",
        t->scatter_ratio);
  }
  if (const std::optional<GyroTimeOffset>& lag = g.time_offset) {
    Say("  time offset  the gyro's readings %s the accelerometer's by %.3g +- %.2g ms (from the "
        "%zu turns%s)\n",
        lag->lag_s >= 0 ? "lag" : "lead", std::abs(lag->lag_s) * 1e3, lag->std_s * 1e3, lag->turns,
        lag->at_limit ? "; at the edge of the +-0.5 s searched: at least that" : "");
  }
  Say("\nrotations (the rotation's angle, the angle turned through +- 1 sigma, and the angle "
      "between "
      "the gravity direction it predicts and the one fitted; deg)\n");
  Say("  %5s %5s %9s %9s %18s %10s %10s\n", "from", "to", "time [s]", "angle", "turned", "residual",
      "held-out");
  for (const GyroRotation& r : g.rotations) {
    Say("  %5zu %5zu %9.3f %9.2f %9.2f +- %5.2f %10.4f %10.4f\n", r.from + 1, r.to + 1,
        r.duration_s, r.angle_deg, r.turned_deg, r.turned_std_deg, r.residual_deg, r.heldout_deg);
  }
  if (std::isfinite(g.heldout_rms_deg)) {
    Say("rms direction error %.4f deg; held out %.4f deg (each rotation predicted by a fit "
        "without it)\n",
        g.rms_deg, g.heldout_rms_deg);
  } else {
    Say("rms direction error %.4f deg; not held out\n", g.rms_deg);
  }
  Say("solver    %s\n", g.summary.termination_message.c_str());
}

// The file's provenance: the options given, every input file (with the orientations) by name, size
// and SHA-256 of the bytes read, and the date when one was given.
Provenance MakeProvenance(const CalibrateArgs& args, const LoadedInput& in,
                          const OrientationFile* orientations, const GyroRun* gyro) {
  Provenance provenance;
  provenance.command = "accelcal calibrate";
  provenance.options = GivenOptionsJson(args.given_options);
  provenance.inputs = InputRecords(in);
  if (orientations != nullptr) {
    provenance.inputs.push_back({args.orientations, orientations->bytes, orientations->sha256});
  }
  if (gyro != nullptr && !args.gyro.empty()) {
    provenance.inputs.push_back(
        {gyro->path, gyro->data.bytes, gyro->data.sha256, gyro->data.stream});
  }
  provenance.date = args.date;
  return provenance;
}

// The end of every calibrate: the file to -o, then the file to stdout (--json) or the summary
// (`input_note`, when not empty, printed after the input's description).
// `mean_sigmas`: the 1σ of each position's mean as the fit took it (empty: none).
// The raw unit's label: --raw-units when given, else the unit every input's binary-log stream
// has by its specification (PX4's sensor_accel, ArduPilot's IMU, a ROS Imu: m/s2), else "raw".
std::string RawUnitLabel(const CalibrateArgs& args, const LoadedInput& in) {
  for (const auto& [name, values] : args.given_options) {
    if (name == "raw-units") return args.raw_units;
  }
  std::string unit;
  for (const LoadedFile& f : in.files) {
    if (!f.data.stream || f.data.stream->unit.empty()) return args.raw_units;
    if (!unit.empty() && unit != f.data.stream->unit) return args.raw_units;
    unit = f.data.stream->unit;
  }
  return unit.empty() ? args.raw_units : unit;
}

// The middle time of each position's still interval [s], or why the positions have none: a
// positions file holds means only, and the clocks of several files are not one time.
std::vector<double> PositionTimes(const LoadedInput& in, std::string* why) {
  if (in.files.size() > 1) {
    *why = "the positions come from " + std::to_string(in.files.size()) +
           " files, whose times are not one clock";
    return {};
  }
  std::vector<double> times;
  for (const Position& p : in.positions) {
    if (!p.interval) {
      *why = in.files.front().path +
             " holds the positions' means without their times (a raw log gives them)";
      return {};
    }
    times.push_back(0.5 * (p.interval->t_begin_s + p.interval->t_end_s));
  }
  return times;
}

// The longest pause between two positions when it is over 5 times the median pause and a minute:
// a drift is fitted straight (or between knots) across it, which nothing between them checks.
void WarnDriftAcrossGap(const std::string& path, const std::vector<double>& times,
                        const BiasModel& model) {
  if (model.constant() || times.size() < 3) return;
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> pauses;
  std::size_t longest = 0;
  for (std::size_t k = 1; k < sorted.size(); ++k) {
    pauses.push_back(sorted[k] - sorted[k - 1]);
    if (pauses.back() > pauses[longest]) longest = pauses.size() - 1;
  }
  std::vector<double> ordered = pauses;
  std::nth_element(ordered.begin(), ordered.begin() + ordered.size() / 2, ordered.end());
  const double median = ordered[ordered.size() / 2];
  if (pauses[longest] > 5 * median && pauses[longest] > 60) {
    Warn(
        "%s: no position between %.6g s and %.6g s (%.0f s, %.0f times the median pause): the %s "
        "bias is fitted across that time as if it drifted as it did around it\n",
        path.c_str(), sorted[longest], sorted[longest + 1], pauses[longest],
        pauses[longest] / median, ToString(model).c_str());
  }
}

int WriteCalibration(const CalibrateArgs& given, const LoadedInput& in, const Gravity& g,
                     const CalibrationResult& result, const std::vector<Vec3>& mean_sigmas,
                     const ModelSelection* selection, const BiasModelSelection* bias_selection,
                     const std::string& input_note, const OrientationFile* orientations = nullptr,
                     const GyroRun* gyro = nullptr, const std::string& thermal_text = "") {
  CalibrateArgs args = given;
  args.raw_units = RawUnitLabel(given, in);
  DiagnosisInput diagnosis_input;
  diagnosis_input.result = &result;
  diagnosis_input.positions = &in.positions;
  diagnosis_input.max_excluded = args.outliers.max_excluded;
  diagnosis_input.selection = selection;
  for (const LoadedFile& f : in.files) {
    if (f.data.kind == InputKind::kRaw) {
      diagnosis_input.logs.push_back({f.path, &f.data.raw, &*f.detection});
    }
  }
  diagnosis_input.unit = g.unit;
  if (gyro != nullptr) diagnosis_input.gyroscope = &gyro->calibration;
  for (const LoadedFile& f : in.files) {
    diagnosis_input.positions_by_row_count |= f.data.kind_from_row_count;
  }
  const Diagnosis diagnosis = Diagnose(diagnosis_input);
  CalibrationFileInfo info;
  info.unit = g.unit;
  info.raw_unit = args.raw_units;
  info.source = args.input.path;
  if (in.files.size() > 1) {
    for (const LoadedFile& f : in.files) info.sources.push_back(f.path);
    for (const std::string& file : in.position_file) {
      info.position_source.push_back(static_cast<int>(
          std::find(info.sources.begin(), info.sources.end(), file) - info.sources.begin()));
    }
  }
  info.positions = in.positions;
  info.mean_sigmas = mean_sigmas;
  info.model_selection = selection;
  info.model_requested = args.model;
  info.bias_model_selection = bias_selection;
  info.diagnosis = &diagnosis;
  info.provenance = MakeProvenance(args, in, orientations, gyro);
  if (gyro != nullptr) {
    info.gyroscope = &gyro->calibration;
    info.gyro_source = gyro->path;
    info.gyro_raw_unit = GyroRawLabel(*gyro, args);
  }
  const std::string json = CalibrationToJson(result, info);
  // Everything is rendered before anything is written: a failure leaves no file behind.
  std::string report;
  if (!args.report.empty()) {
    ReportInput input;
    input.calibration_name = args.output.empty() ? args.input.path : args.output;
    input.calibration = ParseCalibrationJson(json, input.calibration_name);
    if (const LoadedFile* raw = in.FirstRaw()) {  // the report plots one log: the first
      input.log = &raw->data.raw;
      input.rejected = raw->detection->rejected;
    }
    report = RenderReport(input);
  }
  {  // both files or neither
    std::optional<OutputFile> file, report_file;
    if (!args.output.empty()) file.emplace(args.output).Write(json);
    if (!args.report.empty()) report_file.emplace(args.report).Write(report);
    CommitAll({file ? &*file : nullptr, report_file ? &*report_file : nullptr});
  }
  const std::vector<double> errors = GravityNormErrors(result, Means(in.positions));
  for (const OutlierFinding& o : result.outliers) {
    Warn("%s: %s%s\n", args.input.path.c_str(),
         OutlierMessage(o, in.positions, errors,
                        g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g", in.position_file)
             .c_str(),
         o.excluded ? " It was left out of the fit." : " It was kept in the fit.");
  }
  PrintFindings(diagnosis, args.input.path, gyro != nullptr ? gyro->path : args.input.path);
  if (args.json) {
    WriteFileAtomically("-", json);
  } else {
    PrintInput(in);
    Say("%s", input_note.c_str());
    PrintCalibration(result, in.positions, in.position_file, g, args.raw_units);
    Say("%s", thermal_text.c_str());
    if (selection) PrintModelSelection(*selection, args.model == "auto");
    if (bias_selection) {
      Say("bias      auto -> %s: %s\n", ToString(bias_selection->chosen).c_str(),
          bias_selection->reason.c_str());
    }
    if (gyro != nullptr) {
      PrintGyro(*gyro, GyroRawLabel(*gyro, args),
                g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g");
    }
    for (const Finding& f : diagnosis.findings) {
      if (f.severity == Severity::kNote) Say("note      %s\n", f.message.c_str());
    }
    Say("verdict   %s\n", std::string(ToString(diagnosis.verdict())).c_str());
    if (!args.output.empty()) Say("wrote     %s\n", args.output.c_str());
    if (!args.report.empty()) Say("report    %s\n", args.report.c_str());
  }
  if (diagnosis.verdict() == Verdict::kFailed) {
    WriteErr(
        Format("accelcal: %s: the calibration failed its checks: written, but marked "
               "\"verdict\": \"failed\"; do not use it as it is\n",
               args.input.path.c_str()));
    return kExitFailedChecks;
  }
  return kExitOk;
}

// --bias-random-walk or --noise: the bias's random walk q [m/s²/√s] per axis, and where it is from.
struct RandomWalkArg {
  Vec3 q_ms2 = Vec3::Zero();
  std::string source;                                       // empty: not given
  std::array<bool, 3> upper_bound = {false, false, false};  // the noise file's 95 % upper bound
  bool given() const { return !source.empty(); }
};

// A bias random walk below 1e-12 m/s²/√s is none (1 ng after a day); above 1e3 it would move the
// bias by a hundred g in a second.
constexpr double kMinRandomWalk = 1e-12, kMaxRandomWalk = 1e3;

// Usage errors before anything is read; the noise file read (small). `spline`: the bias model
// asked for can take the prior (spline:K, or auto with its spline candidates).
RandomWalkArg ParseRandomWalk(const CalibrateArgs& args, bool spline) {
  RandomWalkArg out;
  const std::vector<double>& v = args.bias_random_walk;
  if (v.empty() && args.noise.empty()) return out;
  const std::string flag = args.noise.empty() ? "--bias-random-walk" : "--noise";
  if (!spline) {
    throw UsageError(flag + " is the random-walk prior of a spline bias: give --bias-model " +
                     "spline:K or auto with it, not " + args.bias_model);
  }
  if (!args.noise.empty()) {
    const ImuNoise noise =
        ParseNoiseJson(ReadFileToString(args.noise, kMaxSmallFileBytes), args.noise);
    out.q_ms2 = noise.accelerometer.random_walk;
    for (std::size_t a = 0; a < 3; ++a) {
      out.upper_bound[a] = !noise.accelerometer.random_walk_resolved[a];
      const double q = out.q_ms2(static_cast<Eigen::Index>(a));
      if (!(q >= kMinRandomWalk && q <= kMaxRandomWalk)) {
        throw DataError(
            Format("%s: the accelerometer's random walk on %c, %g m/s^2/sqrt(s), is "
                   "outside %g to %g: not a bias's random walk",
                   args.noise.c_str(), "xyz"[a], q, kMinRandomWalk, kMaxRandomWalk));
      }
    }
    out.source = args.noise;
    return out;
  }
  if (v.size() != 1 && v.size() != 3) {
    throw UsageError("--bias-random-walk takes one value or three (x,y,z), not " +
                     std::to_string(v.size()) + " (the decimal point is '.')");
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const double q = v.size() == 1 ? v[0] : v[i];
    if (!(q >= kMinRandomWalk && q <= kMaxRandomWalk)) {
      throw UsageError(Format("--bias-random-walk must be from %g to %g m/s^2/sqrt(s), not %g",
                              kMinRandomWalk, kMaxRandomWalk, q));
    }
    out.q_ms2(static_cast<Eigen::Index>(i)) = q;
  }
  out.source = "--bias-random-walk";
  return out;
}

// q in raw units per √s: K q per axis (the walk of specific force w shows as K w in the readings),
// K from a constant-bias fit of the positions; its line of the summary appended to `note`.
Vec3 RandomWalkInRaw(const RandomWalkArg& walk, const std::vector<Vec3>& means,
                     const CalibrationOptions& options, const Gravity& g, const std::string& path,
                     std::string* note) {
  if (options.reading_sigmas.empty()) {
    throw DataError("a random walk of the bias weighs each position by the noise of its samples: " +
                    path + " has positions without samples (give the raw log)");
  }
  CalibrationOptions constant = options;
  constant.model = ModelKind::kLinear;
  constant.bias_model = BiasModel{};
  constant.position_times_s.clear();
  constant.cross_validate = false;
  constant.reading_sigmas.clear();
  const CalibrationResult fit = Calibrate(means, constant);
  const Vec3 q_unit = walk.q_ms2 * (g.in_unit / g.ms2);
  const Vec3 q_raw = (fit.params.K.cwiseAbs2() * q_unit.cwiseAbs2()).cwiseSqrt();
  std::string bounds;
  for (std::size_t a = 0; a < 3; ++a) {
    if (walk.upper_bound[a]) bounds += std::string(bounds.empty() ? "" : ", ") + "xyz"[a];
  }
  if (!bounds.empty()) {
    bounds = "; " + bounds + ": its 95% upper bound, the noise log does not resolve " +
             (bounds.size() > 1 ? "them" : "it");
  }
  *note += Format("prior     bias random walk %s m/s^2/sqrt(s) (%s%s): %s raw/sqrt(s)\n",
                  Vec(walk.q_ms2, " %.3g").c_str() + 1, walk.source.c_str(), bounds.c_str(),
                  Vec(q_raw, " %.3g").c_str() + 1);
  if (!(q_raw.allFinite() && q_raw.minCoeff() > 0)) {
    throw DataError(
        Format("the bias random walk %s m/s^2/sqrt(s) is %s raw/sqrt(s) through K: "
               "outside what this sensor's readings can hold",
               Vec(walk.q_ms2, " %.3g").c_str() + 1, Vec(q_raw, " %.3g").c_str() + 1));
  }
  return q_raw;
}

// calibrate --orientations: the platform-frame least squares of known_orientation.hpp.
int RunCalibrateKnownOrientations(const CalibrateArgs& args) {
  if (!args.gravity_only_options.empty()) {
    throw UsageError(args.gravity_only_options.front() +
                     " does not apply with --orientations (a closed-form fit in the platform "
                     "frame)");
  }
  if (args.model == "auto") {
    throw UsageError("--model auto is not available with --orientations: give linear or quadratic");
  }
  KnownOrientationOptions options;
  options.model = ParseChoice<ModelKind>(args.model, "--model");
  options.cross_validate = args.cross_validate;
  options.outliers = ParseOutlierOptions(args.outliers);
  const Gravity g = ResolveGravity(args.gravity);
  options.gravity = g.in_unit;
  if (auto why = options.Validate()) throw UsageError(*why);
  const OrientationFile orientations = ReadOrientations(args.orientations);
  const LoadedInput in = LoadInput(args.input);
  if (orientations.directions.size() != in.positions.size()) {
    throw DataError(args.orientations + " has " + std::to_string(orientations.directions.size()) +
                    " orientations for the " + std::to_string(in.positions.size()) +
                    " positions of " + args.input.path);
  }
  options.reading_sigmas = ReadingSigmas(in);
  const CalibrationResult result =
      CalibrateKnownOrientations(Means(in.positions), orientations.directions, options);
  const std::string note = Format("orient.   %s: %zu known orientations\n",
                                  args.orientations.c_str(), orientations.directions.size());
  if (GyroWanted(args)) {
    // The gyroscope on top of the known directions: its K_g maps into the platform frame.
    const GyroRun gyro = RunGyro(args, in, result);
    return WriteCalibration(args, in, g, result, options.reading_sigmas, nullptr, nullptr, note,
                            &orientations, &gyro);
  }
  return WriteCalibration(args, in, g, result, options.reading_sigmas, nullptr, nullptr, note,
                          &orientations);
}

}  // namespace

// Positions whose temperatures span this much get a note suggesting --thermal: a MEMS part's
// scale moves by 100-300 ppm/K, 0.1-0.3 % over 10 K.
constexpr double kTemperatureSpanNote_K = 10;

// --thermal: "auto" (nothing), or the degrees K,B[,K2] of `model`. Usage errors before anything is
// read.
std::optional<ThermalDegrees> ParseThermal(const CalibrateArgs& args, ModelKind model) {
  if (args.thermal == "auto") return std::nullopt;
  std::vector<int> d;
  std::stringstream list(args.thermal);
  for (std::string item; std::getline(list, item, ',');) {
    if (item.size() != 1 || item[0] < '0' || item[0] > '9') {
      throw UsageError("--thermal: '" + args.thermal +
                       "' is neither auto nor the degrees K,B[,K2] (whole numbers from 0 to " +
                       std::to_string(kMaxThermalDegree) + ")");
    }
    d.push_back(item[0] - '0');
  }
  if (d.size() < 2 || d.size() > 3 || args.thermal.back() == ',') {
    throw UsageError("--thermal: '" + args.thermal +
                     "' is neither auto nor the degrees K,B[,K2] (e.g. 1,1)");
  }
  const ThermalDegrees degrees{d[0], d[1], d.size() > 2 ? d[2] : 0};
  try {
    (void)ThermalSlots(model, degrees);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--thermal: ") + e.what());
  }
  if (degrees.Max() == 0) {
    throw UsageError("--thermal " + args.thermal +
                     " has no temperature term: leave --thermal out for parameters constant over "
                     "temperature");
  }
  return degrees;
}

// Each position's temperature: its file's from --temperatures, else its own (read with its log).
std::vector<double> PositionTemperatures(const CalibrateArgs& args, LoadedInput* in,
                                         std::string* note) {
  std::vector<double> temps;
  if (!args.temperatures_c.empty()) {
    bool own = false;
    for (std::size_t k = 0; k < in->positions.size(); ++k) {
      const std::string& file = in->position_file.empty() ? args.input.path : in->position_file[k];
      std::size_t i = 0;
      while (i < in->files.size() && in->files[i].path != file) ++i;
      own |= in->positions[k].temperature_c.has_value();
      const double t = args.temperatures_c.at(i) + 0.0;  // -0 written as 0
      in->positions[k].temperature_c = t;
      temps.push_back(t);
    }
    if (own) {
      *note += "          temperatures: --temperatures, one per file, not the logs' own readings\n";
    }
    return temps;
  }
  for (std::size_t k = 0; k < in->positions.size(); ++k) {
    const Position& p = in->positions[k];
    if (!p.temperature_c) {
      const std::string& file = in->position_file.empty() ? args.input.path : in->position_file[k];
      // A column found by its name whose values were no temperature (kelvin, counts) was left
      // out with a note: said here, where it matters.
      std::string left_out;
      for (const LoadedFile& f : in->files) {
        if (f.path == file && !f.data.raw.temperature_note.empty()) {
          left_out = " (" + f.data.raw.temperature_note + ")";
        }
      }
      throw InputError(file, 0,
                       "--thermal needs each position's temperature, and position " +
                           std::to_string(k + 1) + " has none" + left_out +
                           ": give the log's temperature column (--temperature-column) or one "
                           "temperature per file (--temperatures)");
    }
    temps.push_back(*p.temperature_c);
  }
  return temps;
}

// The temperature terms fitted, each in engineering units per K^d (x-first frame).
std::string ThermalText(const CalibrationResult& r, const ThermalDegreeSelection* selection,
                        const Gravity& g, const std::string& raw_unit) {
  const ThermalTerms& t = *r.thermal;
  const auto [lo, hi] = std::minmax_element(t.temperatures_c.begin(), t.temperatures_c.end());
  std::string out = Format(
      "\nthermal   degrees %s%s, T_ref %.4g degC (the parameters above are at T_ref), positions "
      "from %.4g to %.4g degC\n",
      t.params.degrees.ToString().c_str(), selection != nullptr ? " (auto)" : "", t.params.t_ref_c,
      *lo, *hi);
  if (selection != nullptr) out += "          auto: " + selection->reason + "\n";
  out += Format("          coefficients per K^d (K in %s per %s, b in %s; +- 1 sigma)\n",
                raw_unit.c_str(), g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g",
                raw_unit.c_str());
  const std::vector<ThermalSlot> slots = ThermalSlots(r.model, t.params.degrees);
  const Eigen::VectorXd x = Pack(t.params, r.model);
  const bool have_std = t.covariance.rows() == x.size();
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (slots[i].degree == 0) continue;
    const auto idx = static_cast<Eigen::Index>(i);
    const EngineeringValue e = ThermalEngineering(slots[i], x(idx), r.params.K, r.gravity);
    out += Format("  %-5s d%d %14.6g", std::string(slots[i].slot.name).c_str(), slots[i].degree,
                  x(idx));
    if (have_std) {
      const double sd = std::sqrt(t.covariance(idx, idx));
      out += Format(" +- %-9.2g (%.4g +- %.2g %s)\n", sd, e.value,
                    ThermalEngineering(slots[i], sd, r.params.K, r.gravity).value, e.unit.c_str());
    } else {
      out += Format(" (%.4g %s)\n", e.value, e.unit.c_str());
    }
  }
  return out;
}

// calibrate --thermal: the joint fit with parameters that follow temperature, from positions at
// several temperatures (several files, or one ramp).
int RunCalibrateThermal(const CalibrateArgs& args, const CalibrationOptions& options,
                        const std::optional<ThermalDegrees>& degrees, const Gravity& g) {
  std::optional<GyroLogAhead> gyro_ahead;
  if (GyroWanted(args)) gyro_ahead.emplace(args);
  LoadedInput in = LoadInput(args.input);
  std::string note;
  ThermalOptions thermal;
  thermal.base = options;
  thermal.temperatures_c = PositionTemperatures(args, &in, &note);
  thermal.cross_validate = args.cross_validate;
  if (options.outliers.policy != OutlierPolicy::kOff) {
    note +=
        "          outliers: not screened with --thermal (a discordant position shows in "
        "its held-out error)\n";
  }
  const std::vector<Vec3> means = Means(in.positions);
  std::optional<ThermalDegreeSelection> selection;
  ThermalResult fit;
  try {
    if (degrees) {
      thermal.degrees = *degrees;
      fit = CalibrateThermal(means, thermal);
    } else {
      selection = SelectThermalDegrees(means, thermal);
      fit = selection->result;
    }
  } catch (const DataError& e) {
    throw DataError(std::string("--thermal: ") + e.what());
  }
  const CalibrationResult result = AsCalibrationResult(fit, thermal.temperatures_c);
  if (!result.summary.converged()) {
    WriteErr(Format("accelcal: %s: the solver did not converge: %s; nothing written\n",
                    args.input.path.c_str(), result.summary.termination_message.c_str()));
    return kExitNotConverged;
  }
  std::optional<GyroRun> gyro;
  if (gyro_ahead) gyro = RunGyro(args, in, result, &*gyro_ahead);
  return WriteCalibration(
      args, in, g, result, {}, nullptr, nullptr, note, nullptr, gyro ? &*gyro : nullptr,
      ThermalText(result, selection ? &*selection : nullptr, g, RawUnitLabel(args, in)));
}

int RunCalibrate(const CalibrateArgs& args) {
  if (args.date_given) {
    if (const auto why = CheckProvenanceDate(args.date)) throw UsageError("--date: " + *why);
  }
  {
    std::vector<std::string> inputs = args.input.more_paths;
    inputs.push_back(args.input.path);
    inputs.push_back(args.orientations);
    inputs.push_back(args.gyro);
    inputs.push_back(args.noise);
    CheckOutputs({{"-o", args.output}, {"--report", args.report}}, inputs);
  }
  if (GyroWanted(args)) {  // usage errors before anything is read
    GyroOptions(args);
    CheckGyroColumns(args.input, args.gyro, args.gyro_columns);
  }
  const bool thermal = !args.thermal.empty();
  if (!args.temperatures_c.empty()) {
    if (!thermal) throw UsageError("--temperatures are for --thermal: give it too");
    const std::size_t files = 1 + args.input.more_paths.size();
    if (args.temperatures_c.size() != files) {
      throw UsageError(Format("--temperatures: %zu given for %zu input file%s: one per file",
                              args.temperatures_c.size(), files, files == 1 ? "" : "s"));
    }
    for (double t : args.temperatures_c) {
      if (!InTemperatureRange(t)) {
        throw UsageError(Format("--temperatures: %g is outside %g to %g degC", t,
                                kTemperatureRange_C[0], kTemperatureRange_C[1]));
      }
    }
  }
  if (thermal) {
    const char* with = !args.orientations.empty()       ? "--orientations"
                       : args.bias_model != "constant"  ? "--bias-model"
                       : args.model == "auto"           ? "--model auto"
                       : args.method != "joint"         ? "--method"
                       : args.frame != "x-first"        ? "--frame"
                       : args.estimator != "ml"         ? "--estimator"
                       : !args.bias_random_walk.empty() ? "--bias-random-walk"
                       : !args.noise.empty()            ? "--noise"
                                                        : nullptr;
    if (with != nullptr) {
      throw UsageError(std::string("--thermal is the joint maximum-likelihood fit (--method joint, "
                                   "--estimator ml, --frame x-first) of a model chosen by --model "
                                   "linear or quadratic, with a bias constant in time: not with ") +
                       with);
    }
    if (GyroWanted(args) && !args.input.more_paths.empty()) {
      throw UsageError(
          "--thermal with --gyro calibrates the gyroscope from one recording through the "
          "temperatures (a ramp, its turns between the positions): give one INPUT");
    }
    if (args.thermal == "auto" && !args.cross_validate) {
      throw UsageError(
          "--thermal auto decides on held-out error: it needs the cross-validation that "
          "--no-crossval turns off");
    }
  }
  if (!args.orientations.empty()) return RunCalibrateKnownOrientations(args);
  CalibrationOptions options;
  const bool auto_model = args.model == "auto";
  options.model = auto_model ? ModelKind::kLinear
                             : ParseEnum(ModelKindFromString(args.model), args.model, "--model",
                                         (NameList<ModelKind>() + ", auto").c_str());
  options.method = ParseChoice<SolverMethod>(args.method, "--method", kOrientationFreeMethods);
  if (GyroWanted(args) && !IsMaximumLikelihood(options.method)) {
    throw UsageError(
        "--gyro and --gyro-columns need a maximum-likelihood --method (joint, "
        "two-step or newton-lagrange): the gyroscope's fit weighs the "
        "accelerometer by the residual of its fit, which " +
        args.method + " does not estimate");
  }
  options.initialization = ParseChoice<Initialization>(args.init, "--init", kInitializations);
  if (args.frame == "platform") {
    throw UsageError(
        "--frame platform is the frame of known orientations: give them with "
        "--orientations");
  }
  options.frame = ParseChoice<Frame>(args.frame, "--frame", {Frame::kXFirst, Frame::kZFirst});
  options.estimator = ParseChoice<Estimator>(args.estimator, "--estimator");
  const bool auto_bias = args.bias_model == "auto";
  if (!auto_bias) {
    const std::optional<BiasModel> bias = BiasModelFromString(args.bias_model);
    if (!bias) {
      throw UsageError("--bias-model: '" + args.bias_model +
                       "' is none of constant, linear, spline:K (K from 2 to " +
                       std::to_string(kMaxBiasKnots) + ") or auto");
    }
    options.bias_model = *bias;
  }
  options.outliers = ParseOutlierOptions(args.outliers);
  options.cross_validate = args.cross_validate;
  const RandomWalkArg random_walk =
      ParseRandomWalk(args, auto_bias || options.bias_model.kind == BiasModelKind::kSpline);
  if (args.bias_model != "constant" && GyroWanted(args)) {
    throw UsageError("--bias-model " + args.bias_model +
                     " does not apply with the gyroscope: the joint fit with its rotations "
                     "takes the accelerometer's bias as constant");
  }
  if (auto_bias && !args.cross_validate) {
    throw UsageError(
        "--bias-model auto decides on held-out error: it needs the cross-validation that "
        "--no-crossval turns off");
  }
  if (auto_model && !args.cross_validate) {
    throw UsageError(
        "--model auto decides on held-out error: it needs the cross-validation that "
        "--no-crossval turns off");
  }
  const Gravity g = ResolveGravity(args.gravity);
  options.gravity = g.in_unit;
  if (args.max_iterations > 0) {
    options.two_step.max_sweeps = args.max_iterations;
    options.joint.max_iterations = args.max_iterations;
    options.modulus.max_iterations = args.max_iterations;
    options.newton_lagrange.max_iterations = args.max_iterations;
  }
  if (auto why = options.Validate()) throw UsageError(*why);
  if (auto_bias) {  // its candidates must be fittable as the options stand
    CalibrationOptions drifting = options;
    drifting.bias_model = BiasModel{BiasModelKind::kLinear, 0};
    if (auto why = drifting.Validate()) throw UsageError("--bias-model auto: " + *why);
  }
  if (auto_model) {
    CalibrationOptions quadratic = options;
    quadratic.model = ModelKind::kQuadratic;
    if (auto why = quadratic.Validate()) throw UsageError("--model auto: " + *why);
  }
  if (thermal) return RunCalibrateThermal(args, options, ParseThermal(args, options.model), g);
  std::optional<GyroLogAhead> gyro_ahead;
  if (GyroWanted(args)) gyro_ahead.emplace(args);
  const LoadedInput in = LoadInput(args.input);
  const std::vector<Vec3> means = Means(in.positions);
  options.reading_sigmas = ReadingSigmas(in);  // empty: noise from the residuals
  std::string note;
  {  // positions recorded over a span of temperature, calibrated as if it did not matter
    double lo = kTemperatureRange_C[1], hi = kTemperatureRange_C[0];
    for (const Position& p : in.positions) {
      if (p.temperature_c) lo = std::min(lo, *p.temperature_c), hi = std::max(hi, *p.temperature_c);
    }
    if (hi - lo >= kTemperatureSpanNote_K) {
      note += Format(
          "          temperature: the positions span %.3g K (%.4g to %.4g degC); parameters that "
          "follow it (--thermal auto) may describe them better\n",
          hi - lo, lo, hi);
    }
  }
  if (random_walk.given()) {
    options.bias_random_walk =
        RandomWalkInRaw(random_walk, means, options, g, args.input.path, &note);
  }
  std::optional<BiasModelSelection> bias_selection;
  if (!options.bias_model.constant() || auto_bias) {
    std::string why;
    options.position_times_s = PositionTimes(in, &why);
    if (!why.empty() && !auto_bias) {
      throw DataError("--bias-model " + args.bias_model + " needs each position's time: " + why);
    }
    if (auto_bias) {
      // With --model auto the bias is chosen under the quadratic model, which holds whichever
      // model is true (so that squared terms are not taken for a drift), then the model under
      // that bias; the linear model when the quadratic one cannot be fitted.
      if (auto_model) {
        CalibrationOptions quadratic = options;
        quadratic.model = ModelKind::kQuadratic;
        try {
          bias_selection = SelectBiasModel(means, quadratic);
        } catch (const DataError&) {  // too few positions for it: the linear model decides
        }
      }
      if (!bias_selection) bias_selection = SelectBiasModel(means, options);
      if (!why.empty()) bias_selection->reason = "no position has a time: " + why;
      options.bias_model = bias_selection->chosen;
      if (options.bias_model.constant()) options.position_times_s.clear();
    }
  }
  // For a quadratic fit (asked for, or a candidate of --model auto) the linear fit is the
  // comparison: both with held-out validation, decided by ModelSelection's rule.
  const ModelChoice choice = CalibrateChoosingModel(means, options, auto_model);
  const CalibrationResult& result = choice.result;
  const std::optional<ModelSelection>& selection = choice.selection;
  if (result.drift) WarnDriftAcrossGap(args.input.path, result.drift->times_s, options.bias_model);
  if (random_walk.given() && !(result.drift && result.drift->random_walk)) {
    note += "          unused: the bias chosen is " + ToString(options.bias_model) +
            ", and the prior is a spline's\n";
  }
  if (!result.summary.converged()) {
    WriteErr(Format("accelcal: %s: the solver did not converge: %s; nothing written\n",
                    args.input.path.c_str(), result.summary.termination_message.c_str()));
    return kExitNotConverged;
  }
  if (GyroWanted(args)) {
    const GyroRun gyro = RunGyro(args, in, result, &*gyro_ahead);
    // The joint fit's accelerometer is the file's: the rotations refined it.
    const CalibrationResult& accel =
        gyro.calibration.accelerometer ? *gyro.calibration.accelerometer : result;
    return WriteCalibration(args, in, g, accel, options.reading_sigmas,
                            selection ? &*selection : nullptr,
                            bias_selection ? &*bias_selection : nullptr, note, nullptr, &gyro);
  }
  return WriteCalibration(args, in, g, result, options.reading_sigmas,
                          selection ? &*selection : nullptr,
                          bias_selection ? &*bias_selection : nullptr, note);
}

}  // namespace accelcal::cli
