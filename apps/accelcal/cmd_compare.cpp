// accelcal compare: every method on the same positions, tabulated.
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

#include "accelcal/calibrate_unit.hpp"
#include "accelcal/compare.hpp"
#include "accelcal/error.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {

namespace {

// One gyroscope estimator and model on the comparison's accelerometer (compare --gyro).
struct GyroRow {
  GyroEstimator estimator;
  GyroModelKind model;
  std::optional<GyroCalibration> result;
  std::string error;
};

// imu_tk's method beside accelcal's estimators, each held out turn by turn, on the accelerometer
// of the comparison's first maximum-likelihood fit.
std::vector<GyroRow> CompareGyro(const CompareArgs& args, GyroUnit unit, const LoadedInput& in,
                                 const Comparison& comparison) {
  const RawLog& accel_log = TheRawLogForGyro(in);
  const MethodComparison* accel = nullptr;
  for (const MethodComparison& r : comparison.methods) {
    if (!r.error && IsMaximumLikelihood(r.method)) {
      accel = &r;
      break;
    }
  }
  if (accel == nullptr) {
    throw UsageError(
        "--gyro needs a maximum-likelihood method among --methods (its gravity directions)");
  }
  const InputData gyro = ReadGyroLog(args.input, args.gyro, false);
  const std::string subject = DataSubject();
  DataSubject() = args.gyro.log.empty() ? args.input.path : args.gyro.log;
  CheckGyroClock(accel_log, gyro.raw);  // refused once, not in every row
  std::vector<GyroRow> rows = {{GyroEstimator::kImuTk, GyroModelKind::kLinear, {}, {}},
                               {GyroEstimator::kTwoStage, GyroModelKind::kLinear, {}, {}},
                               {GyroEstimator::kTwoStage, GyroModelKind::kGSensitive, {}, {}},
                               {GyroEstimator::kJoint, GyroModelKind::kLinear, {}, {}},
                               {GyroEstimator::kJoint, GyroModelKind::kGSensitive, {}, {}}};
  for (GyroRow& row : rows) {
    GyroCalibrationOptions o;
    o.unit = unit;
    o.estimator = row.estimator;
    o.model = row.model;
    try {
      row.result = CalibrateGyro(accel_log, gyro.raw, in.positions, accel->result, o);
    } catch (const DataError& e) {
      row.error = e.what();
    }
  }
  bool any = false;
  for (const GyroRow& row : rows) any = any || row.result.has_value();
  if (!any) throw DataError(rows.front().error);  // as calibrate refuses it
  DataSubject() = subject;
  return rows;
}

// compare --gyro: the gyroscope's log, or its columns in the accelerometer's.
bool GyroWanted(const CompareArgs& args) { return args.gyro.given(); }

// The options --model, --init, --methods, --outliers and the gravity (in `g`) give.
CompareOptions CompareOptionsOf(const CompareArgs& args, Gravity* g) {
  CompareOptions options;
  options.base.model = ParseChoice<ModelKind>(args.model, "--model");
  options.base.initialization = ParseChoice<Initialization>(args.init, "--init", kInitializations);
  *g = ResolveGravity(args.gravity);
  options.base.gravity = g->in_unit;
  options.leave_one_out = args.leave_one_out;
  if (!args.reference.empty()) {
    options.reference =
        ParseCalibrationJson(ReadFileToString(args.reference, kMaxSmallFileBytes), args.reference)
            .params;
  }
  for (const std::string& name : args.methods) {
    options.methods.push_back(
        ParseChoice<SolverMethod>(name, "--methods", kOrientationFreeMethods));
  }
  options.base.outliers = ParseOutlierOptions(args.outliers);
  if (auto why = options.base.Validate()) throw OptionError(*why);
  for (SolverMethod m : options.methods) {
    CalibrationOptions o = options.base;
    o.method = m;
    if (auto why = o.Validate()) throw OptionError(*why);
  }
  return options;
}

// The screening's findings, with |f| - g under the first maximum-likelihood fit (all methods
// were fitted to the same positions).
void WarnOutliers(const CompareArgs& args, const LoadedInput& in, const std::vector<Vec3>& means,
                  const Comparison& comparison, const CompareOptions& options, const char* unit) {
  const std::vector<MethodComparison>& rows = comparison.methods;
  const MethodComparison* reference = nullptr;
  for (const MethodComparison& r : rows) {
    if (!r.error && (reference == nullptr ||
                     (IsMaximumLikelihood(r.method) && !IsMaximumLikelihood(reference->method)))) {
      reference = &r;
    }
  }
  const std::vector<double> errors =
      reference != nullptr
          ? GravityNormErrors(reference->result.params, means, options.base.gravity)
          : std::vector<double>(means.size(), std::nan(""));
  for (const OutlierFinding& o : comparison.outliers) {
    Warn("%s: %s%s\n", args.input.path.c_str(),
         OutlierMessage(o, in.positions, errors, unit, in.position_file).c_str(),
         o.excluded ? " It was left out of every method's fit." : " It was kept in the fits.");
  }
}

std::string CompareJson(const CompareArgs& args, const Gravity& g, const std::vector<Vec3>& means,
                        const Comparison& comparison, const CompareOptions& options,
                        const std::vector<GyroRow>& gyro_rows) {
  const std::vector<MethodComparison>& rows = comparison.methods;
  const std::vector<ParameterSlot>& slots = ParameterSlots(options.base.model);
  const bool gyro_wanted = GyroWanted(args);
  // Numbers shortest round-trip, failures null with the reason. No timings: output is
  // reproducible.
  using Json = nlohmann::ordered_json;
  const auto number = [](const std::optional<double>& v) { return v ? Json(*v) : Json(); };
  Json doc;
  doc["source"] = args.input.path;
  doc["model"] = ToString(options.base.model);
  doc["gravity"] = g.in_unit;
  doc["positions"] = means.size();
  doc["positions_used"] = comparison.positions_used.size();
  Json& outliers = doc["outliers"] = Json::array();
  for (const OutlierFinding& o : comparison.outliers) {
    outliers.push_back({{"position", o.position + 1},
                        {"excluded", o.excluded},
                        {"t", number(o.t)},
                        {"threshold", number(o.threshold)}});
  }
  if (!comparison.outlier_note.empty()) doc["outlier_note"] = comparison.outlier_note;
  Json& methods = doc["methods"] = Json::array();
  for (const MethodComparison& r : rows) {
    Json row;
    row["method"] = ToString(r.method);
    if (r.error) {
      row["error"] = *r.error;
      methods.push_back(std::move(row));
      continue;
    }
    const Eigen::VectorXd theta = Pack(r.result.params, options.base.model);
    Json& parameters = row["parameters"] = Json::object();
    for (std::size_t j = 0; j < slots.size(); ++j) {
      parameters[std::string(slots[j].name)] = theta(static_cast<Eigen::Index>(j));
    }
    row["modular_square_mean"] = number(r.modular_square_mean);
    row["modular_square_std"] = number(r.modular_square_std);
    row["gravity_norm_rms"] = number(r.gravity_norm_rms);
    row["leave_one_out_rms"] = number(r.leave_one_out_rms);
    if (r.leave_one_out_error) row["leave_one_out_error"] = *r.leave_one_out_error;
    if (r.leave_one_out_from) row["leave_one_out_from"] = ToString(*r.leave_one_out_from);
    if (r.against_reference) {
      row["e_T_percent"] = number(r.against_reference->e_T_percent);
      row["e_b_percent"] = number(r.against_reference->e_b_percent);
    }
    row["iterations"] = r.result.summary.iterations;
    methods.push_back(std::move(row));
  }
  if (gyro_wanted) {
    Json& gyro = doc["gyroscope"] = Json::array();
    for (const GyroRow& r : gyro_rows) {
      Json row = {{"estimator", ToString(r.estimator)}, {"model", ToString(r.model)}};
      if (!r.result) {
        row["error"] = r.error;
      } else {
        row["heldout_rms_deg"] = number(r.result->heldout_rms_deg);
        row["rms_deg"] = r.result->rms_deg;
        Json scales = Json::array();
        for (int i = 0; i < 3; ++i) scales.push_back(r.result->params.K.row(i).norm());
        row["scale_factors_raw_per_rad_s"] = scales;
      }
      gyro.push_back(std::move(row));
    }
  }
  return JsonText(doc);
}

// The gyroscope's rows of the text table (compare --gyro).
std::string GyroText(const CompareArgs& args, const std::vector<GyroRow>& gyro_rows) {
  std::string out;
  out += Format("\ngyroscope %s: direction error of the turns [deg]\n",
                (args.gyro.log.empty() ? args.input.path : args.gyro.log).c_str());
  out += Format("%-10s %-12s %10s %10s   %s\n", "estimator", "model", "held-out", "in fit",
                "scale factors (row norms of K)");
  std::string errors;
  for (const GyroRow& r : gyro_rows) {
    const std::string estimator(ToString(r.estimator)), model(ToString(r.model));
    if (!r.result) {
      out += Format("%-10s %-12s %10s %10s\n", estimator.c_str(), model.c_str(), "-", "-");
      errors += estimator + " " + model + ": " + r.error + "\n";
      continue;
    }
    const GyroCalibration& gc = *r.result;
    out += Format("%-10s %-12s %10.4f %10.4f   %.8g %.8g %.8g\n", estimator.c_str(), model.c_str(),
                  gc.heldout_rms_deg, gc.rms_deg, gc.params.K.row(0).norm(),
                  gc.params.K.row(1).norm(), gc.params.K.row(2).norm());
  }
  out += errors +
         "imutk: imu_tk's method (bias from the first still position, K from the turns, "
         "the accelerometer held);\nheld-out: each turn predicted by a fit without it.\n";
  return out;
}

std::string CompareText(const CompareArgs& args, const Gravity& g, const std::vector<Vec3>& means,
                        const Comparison& comparison, const CompareOptions& options,
                        const std::vector<GyroRow>& gyro_rows) {
  const std::vector<MethodComparison>& rows = comparison.methods;
  const std::vector<ParameterSlot>& slots = ParameterSlots(options.base.model);
  const bool gyro_wanted = GyroWanted(args);
  std::string screened;  // "7, 12": the positions no method was fitted to
  for (const OutlierFinding& o : comparison.outliers) {
    if (o.excluded) screened += (screened.empty() ? "" : ", ") + std::to_string(o.position + 1);
  }
  std::string out;
  out += Format("%s: %zu positions, %s model, gravity %.9g %s\n", args.input.path.c_str(),
                means.size(), std::string(ToString(options.base.model)).c_str(), g.in_unit,
                std::string(ToString(g.unit)).c_str());
  if (!screened.empty()) {
    out += Format("every method fitted to %zu positions: position%s %s left out (screening)\n",
                  comparison.positions_used.size(),
                  screened.find(',') != std::string::npos ? "s" : "", screened.c_str());
  }
  if (!comparison.outlier_note.empty()) out += "screening " + comparison.outlier_note + "\n";
  out += "\n";
  out += Format("%-18s", "");
  for (const MethodComparison& r : rows)
    out += Format("%17s", std::string(ToString(r.method)).c_str());
  out += "\n";
  auto row = [&](const char* label, auto value) {
    out += Format("%-18s", label);
    for (const MethodComparison& r : rows) out += r.error ? Format("%17s", "-") : value(r);
    out += "\n";
  };
  for (std::size_t j = 0; j < slots.size(); ++j) {
    row(std::string(slots[j].name).c_str(), [&](const MethodComparison& r) {
      return Format("%17.10g",
                    Pack(r.result.params, options.base.model)(static_cast<Eigen::Index>(j)));
    });
  }
  row("|f|^2/g^2 mean",
      [](const MethodComparison& r) { return Format("%17.10f", r.modular_square_mean); });
  row("|f|^2/g^2 std",
      [](const MethodComparison& r) { return Format("%17.4e", r.modular_square_std); });
  row("rms |f|-g", [](const MethodComparison& r) { return Format("%17.4e", r.gravity_norm_rms); });
  row("held-out rms", [](const MethodComparison& r) {
    if (!r.leave_one_out_rms) return Format("%17s", "n/a");
    return Format(r.leave_one_out_from ? "%16.4e*" : "%17.4e", *r.leave_one_out_rms);
  });
  if (options.reference) {
    row("e_T [%]", [](const MethodComparison& r) {
      return Format("%17.4f", r.against_reference->e_T_percent);
    });
    row("e_b [%]", [](const MethodComparison& r) {
      return Format("%17.4f", r.against_reference->e_b_percent);
    });
  }
  row("iterations",
      [](const MethodComparison& r) { return Format("%17d", r.result.summary.iterations); });
  row("time [us]",
      [](const MethodComparison& r) { return Format("%17.0f", r.result.summary.time_s * 1e6); });
  for (const MethodComparison& r : rows) {
    if (r.error) out += "\n" + std::string(ToString(r.method)) + ": " + *r.error;
    if (r.leave_one_out_error) {
      out += "\n" + std::string(ToString(r.method)) + " held-out: " + *r.leave_one_out_error;
    }
  }
  out +=
      "\nheld-out rms: |f_k| - g with position k predicted by a fit without it;\n"
      "* shared with the first solver that reached the same optimum (same estimator).\n";
  if (gyro_wanted) out += GyroText(args, gyro_rows);
  return out;
}

}  // namespace

int RunCompare(const CompareArgs& args) {
  Gravity g{};
  const CompareOptions options = CompareOptionsOf(args, &g);
  const bool gyro_wanted = GyroWanted(args);
  GyroUnit gyro_unit = GyroUnit::kRaw;
  if (gyro_wanted) {
    gyro_unit = ParseChoice<GyroUnit>(args.gyro_units, "--gyro-units");
    CheckGyroColumns(args.input, args.gyro);
  }
  const LoadedInput in = LoadInput(args.input);
  const std::vector<Vec3> means = Means(in.positions);
  const Comparison comparison = CompareMethods(means, options);
  const std::vector<GyroRow> gyro_rows =
      gyro_wanted ? CompareGyro(args, gyro_unit, in, comparison) : std::vector<GyroRow>();
  const char* unit = g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g";
  if (!comparison.outliers.empty()) WarnOutliers(args, in, means, comparison, options, unit);
  WriteFileAtomically("-", args.json ? CompareJson(args, g, means, comparison, options, gyro_rows)
                                     : CompareText(args, g, means, comparison, options, gyro_rows));
  return kExitOk;
}

CommandRun SetUpCompare(CLI::App* cmd) {
  auto a = std::make_shared<CompareArgs>();
  cmd->add_option("INPUT", a->input.path, "raw log or positions file")->required();
  AddInputOptions(cmd, &a->input, true);
  AddDetectionOptions(cmd, &a->input);
  AddGravityOptions(cmd, &a->gravity);
  cmd->add_option("--model", a->model, "linear or quadratic")->capture_default_str();
  cmd->add_option("--methods", a->methods, "comma-separated (default: all for the model)")
      ->delimiter(',');
  cmd->add_option("--init", a->init, "auto, ellipsoid or normalized-readings")
      ->capture_default_str();
  cmd->add_flag("!--no-held-out", a->leave_one_out, "skip the leave-one-position-out fits");
  AddOutlierOptions(cmd, &a->outliers,
                    "screen the positions once (maximum-likelihood fit) and fit every method to "
                    "the same ones: exclude a disagreeing position, flag it only, or off");
  cmd->add_option("--reference", a->reference,
                  "a known calibration (JSON): adds paper 001's e_T and e_b per method");
  cmd->add_flag("--json", a->json, "machine-readable output");
  AddSensorInput(cmd, kGyroscopeFlags, &a->gyro,
                 " on the same clock: compare its estimators too (imu_tk's method, two-stage and "
                 "joint, linear and g-sensitive)",
                 "in INPUT or the {log} log");
  AddSensorUnits(cmd, kGyroscopeFlags, &a->gyro_units);
  return [a](const CLI::App& parsed) {
    CheckSensorInput(parsed, kGyroscopeFlags, a->gyro, {"--gyro-units"});
    DataSubject() = a->input.path;
    return RunCompare(*a);
  };
}

}  // namespace accelcal::cli
