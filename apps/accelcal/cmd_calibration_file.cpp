// The commands that use a calibration file: apply, report, export.
#include "commands.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "accelcal/export.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/noise_file.hpp"
#include "accelcal/parameter_file.hpp"
#include "accelcal/report.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {
int RunApply(const ApplyArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration, args.input.path, args.gyro.log});
  const LoadedCalibration cal = ParseCalibrationJson(
      ReadFileToString(args.calibration, kMaxSmallFileBytes), args.calibration);
  RefuseFailed(cal, args.calibration);
  const bool gyro = args.gyro.given();
  if (gyro && !cal.has_gyroscope()) {
    throw UsageError(args.calibration +
                     " holds no gyroscope calibration: --gyro and --gyro-columns need one "
                     "(calibrate --gyro)");
  }
  if (cal.has_gyroscope() && !gyro) {
    Warn(
        "%s: its gyroscope calibration is not applied: give the rates with --gyro or "
        "--gyro-columns\n",
        args.calibration.c_str());
  }
  ForceUnit unit = cal.unit;
  if (args.units) unit = ParseChoice<ForceUnit>(*args.units, "--units");
  double factor = 1.0;  // calibration unit -> output unit
  if (cal.unit == ForceUnit::kMetersPerSecond2 && unit == ForceUnit::kStandardGravity) {
    factor = 1.0 / kStandardGravity_ms2;
  } else if (cal.unit == ForceUnit::kStandardGravity && unit == ForceUnit::kMetersPerSecond2) {
    factor = kStandardGravity_ms2;
  }
  ReadOptions read = MakeReadOptions(args.input);
  read.kind = InputKind::kRaw;
  ProgressBar bar("reading");
  read.progress = bar.ByteCallback();
  const InputData data = ReadInput(args.input.path, read);
  bar.Finish();
  const RawLog& log = data.raw;
  RefuseLeftOutTemperature(cal, log, args.input.path);
  const bool has_time = !log.time_s.empty();
  // Parameters that follow temperature: each reading at its own temperature when the log has
  // them, held to the range the calibration was fitted over (a polynomial is not extrapolated).
  const bool thermal = cal.thermal && log.temperature_c.size() == log.samples.size();
  InputData rates;
  if (gyro) {
    rates = ReadGyroLog(args.input, args.gyro, false);
    CheckGyroClock(log, rates.raw);
  }
  // The gyroscope's offsets over temperature: each rate at the gyro log's temperature, else the
  // accelerometer's at the same sample.
  const GyroThermalBias* gyro_bias =
      gyro && cal.gyroscope->thermal ? &cal.gyroscope->thermal->bias : nullptr;
  const std::string gyro_t_source = gyro ? GyroTemperatureSource(rates.raw, log) : "";
  const bool gyro_thermal = gyro_bias && gyro_bias->degree() > 0 && !gyro_t_source.empty();
  if (gyro_thermal) WarnOtherTemperatureSensor(cal, args.calibration, gyro_t_source, "corrected");
  {
    LoadedCalibration said = cal;
    if (thermal) said.thermal.reset();
    if (gyro_thermal || !gyro) said.gyroscope.reset();
    WarnVaryingNotUsed(said, args.calibration, "applied");
  }
  // Each rate's temperature as calibrate took it: a gap between two readings that have one
  // takes the line between them.
  const std::vector<double> gyro_t =
      gyro_thermal ? GyroSampleTemperatures(rates.raw, log) : std::vector<double>();
  const auto gyro_t_at = [&](std::size_t i) { return gyro_t[i]; };
  double t_min = kTemperatureRange_C[0], t_max = kTemperatureRange_C[1];
  if (thermal && cal.thermal_range_c) std::tie(t_min, t_max) = *cal.thermal_range_c;
  std::size_t held = 0;
  auto params_at = [&, last_t = std::nan(""), last = cal.params](std::size_t i) mutable {
    if (!thermal) return cal.params;
    const double t = log.temperature_c[i];
    if (std::isnan(t)) {
      throw InputError(args.input.path, log.line[i],
                       "the reading has no temperature (" + log.temperature_source +
                           "), which the calibration's parameters follow");
    }
    const double t_held = std::clamp(t, t_min, t_max);
    if (t_held != last_t) last = cal.thermal->params.At(t_held), last_t = t_held;
    return last;
  };
  std::size_t gyro_held = 0;
  // Every reading is checked before anything is written; the output is then streamed.
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    // Said beyond 1 K: the range is the positions' mean temperatures, which single readings
    // straddle by their own scatter.
    if (thermal) held += log.temperature_c[i] < t_min - 1 || log.temperature_c[i] > t_max + 1;
    if (!SpecificForce(params_at(i), log.samples[i])) {
      throw InputError(args.input.path, log.line[i],
                       "the reading lies outside the range the quadratic model can invert");
    }
    if (gyro_thermal) {
      const double t = gyro_t_at(i);
      gyro_held += t < cal.gyroscope->thermal->range_c.first - 1 ||
                   t > cal.gyroscope->thermal->range_c.second + 1;
    }
  }
  OutputFile file(args.output.empty() ? "-" : args.output);  // buffers: one Write per row
  file.Write("# accelcal apply " + VisibleLine(args.calibration) + ": specific force in " +
             std::string(ToString(unit)) + (gyro ? ", body rate in rad/s" : "") + "\n");
  if (log.time) {  // the clock stated once: times are seconds from the first sample
    file.Write("# time: seconds from the first sample, at " + FormatNumber(log.time->origin_s) +
               " s on the log's clock (read in " + std::string(ToString(log.time->unit)) + ")\n");
  }
  if (thermal) {
    file.Write("# temperature: each reading corrected at its own (" +
               VisibleLine(log.temperature_source) + "), held to " + FormatNumber(t_min) + " .. " +
               FormatNumber(t_max) + " degC\n");
  }
  if (gyro_thermal) {
    file.Write("# gyroscope temperature: each rate's offsets at its own (" +
               VisibleLine(gyro_t_source) + "), held to " +
               FormatNumber(cal.gyroscope->thermal->range_c.first) + " .. " +
               FormatNumber(cal.gyroscope->thermal->range_c.second) + " degC\n");
  }
  if (gyro_held > 0) {
    Warn(
        "%s: %zu rates were recorded more than 1 K outside %g .. %g degC, the range the "
        "gyroscope's offsets were fitted over: corrected at the nearest end\n",
        args.input.path.c_str(), gyro_held, cal.gyroscope->thermal->range_c.first,
        cal.gyroscope->thermal->range_c.second);
  }
  if (held > 0) {
    Warn(
        "%s: %zu readings were recorded more than 1 K outside %g .. %g degC, the range the "
        "calibration was fitted over: corrected at the nearest end\n",
        args.input.path.c_str(), held, t_min, t_max);
  }
  file.Write(std::string(has_time ? "time,x,y,z" : "x,y,z") + (gyro ? ",wx,wy,wz\n" : "\n"));
  const Mat33 gyro_K_inverse = gyro ? Mat33(cal.gyroscope->params.K.inverse()) : Mat33::Zero();
  char row[256];
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    const Vec3 f = *SpecificForce(params_at(i), log.samples[i]);
    char* p = row;
    const auto number = [&](double v, char end) {
      p = std::to_chars(p, row + sizeof row, v).ptr;
      *p++ = end;
    };
    if (has_time) number(log.time_s[i], ',');
    for (int a = 0; a < 3; ++a) number(f(a) * factor, a < 2 || gyro ? ',' : '\n');
    if (gyro) {  // w = K_g⁻¹ (raw − b_g(T) − G f), f in the calibration's unit
      const GyroParameters& g = cal.gyroscope->params;
      Vec3 b = g.bias;
      if (gyro_thermal) {
        b += gyro_bias->OffsetChange(std::clamp(gyro_t_at(i), cal.gyroscope->thermal->range_c.first,
                                                cal.gyroscope->thermal->range_c.second));
      }
      const Vec3 w = gyro_K_inverse * (rates.raw.samples[i] - b - g.G * f);
      for (int a = 0; a < 3; ++a) number(w(a), a < 2 ? ',' : '\n');
    }
    file.Write(std::string_view(row, static_cast<std::size_t>(p - row)));
  }
  file.Commit();
  return kExitOk;
}

int RunReport(const ReportArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration, args.log.path});
  ReportInput input;
  input.calibration = ParseCalibrationJson(ReadFileToString(args.calibration, kMaxSmallFileBytes),
                                           args.calibration);
  input.calibration_name = args.calibration;
  InputData data;
  if (!args.log.path.empty()) {
    if (auto why = args.log.detection.Validate()) throw UsageError(*why);
    ReadOptions read = MakeReadOptions(args.log);
    read.kind = InputKind::kRaw;
    data = ReadInput(args.log.path, read);
    input.log = &data.raw;
    // The same detection as calibrate's (same options) says which still periods were not used.
    input.rejected = DetectStaticIntervals(data.raw, args.log.detection).rejected;
  }
  WriteFileAtomically(args.output.empty() ? "-" : args.output, RenderReport(input));
  if (!args.output.empty()) {
    for (const std::string& w : ReportWarnings(input)) Say("warning: %s\n", w.c_str());
    Say("report    %s\n", args.output.c_str());
  }
  return kExitOk;
}

int RunExport(const ExportArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration, args.noise});
  const ExportFormat format = ParseChoice<ExportFormat>(args.format, "--to");
  const std::string text = ReadFileToString(args.calibration, kMaxSmallFileBytes);
  const LoadedCalibration cal = ParseCalibrationJson(text, args.calibration);
  RefuseFailed(cal, args.calibration);
  ExportOptions options;
  options.sensor = args.sensor;
  options.raw_unit = args.raw_unit;
  options.gyro_raw_unit = args.gyro_raw_unit;
  // Unset unless given: PX4's slot is then the log's own for the sensor.
  if (std::find(args.given.begin(), args.given.end(), "instance") != args.given.end()) {
    options.instance = args.instance;
  }
  options.c_prefix = args.c_prefix;
  options.rostopic = args.rostopic;
  if (!args.noise.empty()) {
    options.noise = ParseNoiseJson(ReadFileToString(args.noise, kMaxSmallFileBytes), args.noise);
  }
  options.device_id = args.device_id;
  options.gyro_device_id = args.gyro_device_id;
  if (!args.current_params.empty()) {
    options.current_params = ParseParameterFile(
        ReadFileToString(args.current_params, kMaxSmallFileBytes), args.current_params);
  }
  const bool noise_only = format == ExportFormat::kKalibrImu || format == ExportFormat::kRos;
  // An option given that the format has no use for is refused.
  if (auto why = options.Validate(format, args.given)) throw OptionError(*why);
  ExportResult exported;
  try {
    exported = ExportCalibration(cal, text, format, options);
  } catch (const std::invalid_argument& e) {
    // The targets' refusals that depend on the calibration (ExportOptions::Validate's are
    // refused above, named by their marks).
    throw UsageError(WithFlags(e.what(), {{"instance", "--instance"},
                                          {"gyro_raw_unit", "--gyro-raw-unit"},
                                          {"raw_unit", "--raw-unit"}}));
  } catch (const DataError& e) {
    throw InputError(
        noise_only ? args.noise.empty() ? args.calibration : args.noise : args.calibration, 0,
        WithFlags(e.what(), {{"gyro_raw_unit", "--gyro-raw-unit"},
                             {"raw_unit", "--raw-unit"},
                             {"raw_units", "calibrate --raw-units"},
                             {"current_params", "--current-params FILE.param"}}));
  }
  // The file (or stdout) gets the export alone; what it means and what it lost goes to the
  // terminal: stdout when the export went to a file, else stderr.
  WriteFileAtomically(args.output.empty() ? "-" : args.output, exported.text);
  if (noise_only) {  // the noise alone: no model to lose
    if (CurrentVerbosity() != Verbosity::kQuiet) {
      const std::string what =
          exported.convention +
          "\nthe calibration's model is not in this file (--to kalibr writes Kalibr's)\n";
      args.output.empty() ? WriteErr(what) : WriteOut(what);
    }
    return kExitOk;
  }
  if (cal.has_gyroscope() && !exported.gyroscope_included) {
    if (!exported.gyroscope_omitted.empty()) {
      Warn("%s: its gyroscope calibration is not in this export: %s\n", args.calibration.c_str(),
           WithFlags(exported.gyroscope_omitted, {{"gyro_raw_unit", "--gyro-raw-unit"}}).c_str());
    } else {
      Warn(
          "%s: its gyroscope calibration is not in this export: the %s format holds the "
          "accelerometer's only%s\n",
          args.calibration.c_str(), args.format.c_str(),
          format == ExportFormat::kImuTk ? " (--sensor gyroscope writes the gyroscope's)"
                                         : ", so far");
    }
  }
  std::string note = exported.convention + "\n";
  const ExportLoss& loss = exported.loss;
  const std::string unit_name(ToString(cal.unit));
  const char* unit = unit_name.c_str();
  // With a gyroscope beside it, the loss is the accelerometer's (the gyroscope's is said above).
  const std::string model = cal.has_gyroscope() ? "the accelerometer's model" : "the model";
  note += loss.dropped.empty() ? "exact: nothing of " + model + " is dropped\n"
                               : "dropped: " + loss.dropped + "\n";
  if (args.sensor == "gyroscope") {  // the loss above is the accelerometer's
    note =
        exported.convention + "\n" +
        (exported.gyroscope_dropped.empty() ? "exact: nothing of the gyroscope's model is dropped\n"
                                            : "dropped: " + exported.gyroscope_dropped + "\n");
  } else if (loss.positions > 0 && !loss.dropped.empty()) {
    note += Format(
        "on the calibration's %d positions: corrected specific force off by %.3g %s max, %.3g %s "
        "RMS; RMS of |f| - g %.3g %s (full model %.3g %s)\n",
        loss.positions, loss.max_error, unit, loss.rms_error, unit, loss.norm_rms_export, unit,
        loss.norm_rms_full, unit);
  } else if (!loss.dropped.empty()) {
    note += "the file holds no positions to measure the loss on\n";
  }
  if (args.sensor != "gyroscope" && exported.gyroscope_included) {
    note += exported.gyroscope_dropped.empty()
                ? "exact: nothing of the gyroscope's model is dropped\n"
                : "dropped from the gyroscope: " + exported.gyroscope_dropped + "\n";
  }
  if (CurrentVerbosity() != Verbosity::kQuiet) {
    args.output.empty() ? WriteErr(note) : WriteOut(note);
  }
  return kExitOk;
}

CommandRun SetUpApply(CLI::App* cmd) {
  auto a = std::make_shared<ApplyArgs>();
  cmd->add_option("CAL", a->calibration, "calibration file (JSON)")->required();
  cmd->add_option("LOG", a->input.path, "raw log")->required();
  AddInputOptions(cmd, &a->input, false);
  cmd->add_option("-o,--output", a->output, "output file (default: stdout)")->check(kFileName);
  cmd->add_option("--units", a->units, "output unit m/s2 or g (default: the calibration's)");
  AddSensorInput(cmd, kGyroscopeFlags, &a->gyro, " on the same clock: its body rates [rad/s] too",
                 "in LOG or the {log} log");
  return [a](const CLI::App& parsed) {
    CheckSensorInput(parsed, kGyroscopeFlags, a->gyro, {});
    DataSubject() = a->input.path;
    return RunApply(*a);
  };
}

CommandRun SetUpReport(CLI::App* cmd) {
  auto a = std::make_shared<ReportArgs>();
  cmd->add_option("CAL", a->calibration, "calibration file (JSON)")->required();
  cmd->add_option("LOG", a->log.path, "the raw log it was calibrated from (optional)");
  AddInputOptions(cmd, &a->log, false);
  AddDetectionOptions(cmd, &a->log);
  cmd->add_option("-o,--output", a->output, "HTML file (default: stdout)")->check(kFileName);
  return [a](const CLI::App& /*parsed*/) {
    DataSubject() = a->log.path.empty() ? a->calibration : a->log.path;
    return RunReport(*a);
  };
}

CommandRun SetUpExport(CLI::App* cmd) {
  auto a = std::make_shared<ExportArgs>();
  cmd->add_option("CAL", a->calibration, "calibration file (JSON)")->required();
  cmd->add_option("--to", a->format,
                  "json, yaml, kalibr, px4, ardupilot, c-header, imutk, kalibr-imu, ros, "
                  "openvins or basalt (docs/conventions.md)")
      ->required();
  cmd->add_option("--noise", a->noise,
                  "the sensor's noise (accelcal noise --json, calibrated): kalibr-imu, ros, "
                  "openvins and basalt need it, kalibr writes its keys beside the model")
      ->check(kFileName);
  cmd->add_option("--rostopic", a->rostopic,
                  "the IMU's topic (kalibr-imu, openvins, kalibr with --noise)")
      ->capture_default_str();
  cmd->add_option("-o,--output", a->output, "output file (default: stdout)")->check(kFileName);
  cmd->add_option("--raw-unit", a->raw_unit,
                  "unit of the calibrated raw readings, m/s2 or g, when the file's label "
                  "is another (kalibr, px4, ardupilot need readings in m/s2)");
  cmd->add_option("--gyro-raw-unit", a->gyro_raw_unit,
                  "unit of the gyroscope's calibrated raw rates, rad/s or deg/s, when the "
                  "file's label is another (kalibr, openvins, basalt need rates in rad/s)");
  cmd->add_option("--instance", a->instance,
                  "accelerometer index: PX4 CAL_ACC<n>, ArduPilot INS_ACC / INS_ACC2 / INS_ACC3")
      ->capture_default_str();
  cmd->add_option("--device-id", a->device_id,
                  "px4: the sensor's device id for CAL_ACC<n>_ID (default: the one of the "
                  "ULog stream calibrated)")
      ->check(kDeviceId);
  cmd->add_option("--gyro-device-id", a->gyro_device_id,
                  "px4: the gyroscope's device id for CAL_GYRO<n>_ID (default: the one of the "
                  "ULog stream calibrated)")
      ->check(kDeviceId);
  cmd->add_option("--current-params", a->current_params,
                  "ardupilot: the parameters in force when the log was recorded (.param "
                  "file), composed with a calibration of IMU or ACC records (default: the "
                  "log's PARM values)")
      ->check(kFileName);
  cmd->add_option("--c-prefix", a->c_prefix, "prefix of the C identifiers (c-header)")
      ->capture_default_str();
  cmd->add_option("--sensor", a->sensor,
                  "accelerometer or gyroscope: the triad imutk writes (c-header writes both)")
      ->capture_default_str();
  return [a](const CLI::App& parsed) {
    DataSubject() = a->calibration;
    for (const char* name : {"raw_unit", "gyro_raw_unit", "instance", "c_prefix", "sensor", "noise",
                             "rostopic", "device_id", "gyro_device_id", "current_params"}) {
      std::string flag = std::string("--") + name;
      std::replace(flag.begin(), flag.end(), '_', '-');
      if (parsed.count(flag) > 0) a->given.push_back(name);
    }
    return RunExport(*a);
  };
}

}  // namespace accelcal::cli
