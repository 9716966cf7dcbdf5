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
#include <memory>
#include <sstream>
#include <stdexcept>

#include "accelcal/calibrate_unit.hpp"
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
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {
namespace {

// The label of the gyroscope's raw unit: its declared unit (rad/s, deg/s), or for raw counts the
// accelerometer's raw label when that is a label of counts ("counts", "LSB"), else "raw": an
// accelerometer read in m/s2 or g says nothing of the gyroscope's unit.

void PrintInput(const LoadedInput& in) {
  for (const LoadedFile& f : in.files) {
    if (f.data.kind == InputKind::kPositions) {
      Say("input     %s: %zu positions (%s)\n", Shown(f.path).c_str(), f.data.positions.size(),
          WithReaderFlags(f.data.kind_reason).c_str());
      continue;
    }
    const StaticDetectionResult& d = *f.detection;
    Say("input     %s: raw log, %zu samples at %.6g Hz (%s)\n", Shown(f.path).c_str(),
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
  if (f.code == "temperature_span") return " (--thermal auto)";
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
      WriteErrLine(Format("accelcal: %s: failed check (%s): %s%s\n", path.c_str(), f.code.c_str(),
                          f.message.c_str(), OptionHint(f)));
    } else if (f.severity == Severity::kWarning) {
      Warn("%s: %s%s\n", path.c_str(), f.message.c_str(), OptionHint(f));
    }
  }
}

void PrintGyro(const UnitOutcome::Gyroscope& run, const char* force_unit) {
  const GyroCalibration& g = run.calibration;
  const std::string& raw_unit = run.calibration.raw_unit;
  const auto& slots = GyroParameterSlots(g.model);
  const bool have_std = g.covariance.size() > 0;
  Say("\ngyroscope %s: %zu samples; model %s (%s), %s fit, w_raw = K w + b + G f\n",
      Shown(run.calibration.source).c_str(), run.data.raw.samples.size(),
      std::string(ToString(g.model)).c_str(), g.model_reason.c_str(),
      std::string(ToString(g.estimator)).c_str());
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

bool GyroWanted(const CalibrateArgs& args) { return args.gyro.given(); }

bool Given(const CalibrateArgs& args, const char* flag) {
  const auto& given = args.gravity_only_options;
  return std::find(given.begin(), given.end(), flag) != given.end();
}

// --thermal's degrees K,B[,K2] (none: auto).
std::optional<ThermalDegrees> ParseThermalDegrees(const std::string& text) {
  if (text == "auto") return std::nullopt;
  std::vector<int> d;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    if (item.size() != 1 || item[0] < '0' || item[0] > '9') {
      throw UsageError("--thermal: '" + text +
                       "' is neither auto nor the degrees K,B[,K2] (whole numbers from 0 to " +
                       std::to_string(kMaxThermalDegree) + ")");
    }
    d.push_back(item[0] - '0');
  }
  if (d.size() < 2 || d.size() > 3 || text.back() == ',') {
    throw UsageError("--thermal: '" + text +
                     "' is neither auto nor the degrees K,B[,K2] (e.g. 1,1)");
  }
  return ThermalDegrees{d[0], d[1], d.size() > 2 ? d[2] : 0};
}

// The gyroscope's part of the request (calibrate --gyro / --gyro-columns).
void GyroRequest(const CalibrateArgs& args, UnitRequest* r) {
  r->gyro = args.gyro;
  r->gyro_units = ParseChoice<GyroUnit>(args.gyro_units, "--gyro-units");
  if (!args.gyro_estimator.empty()) {
    r->gyro_estimator = ParseChoice<GyroEstimator>(args.gyro_estimator, "--gyro-estimator");
  }
  if (args.gyro_thermal == "auto") {
    r->gyro_thermal_auto = true;
  } else if (!args.gyro_thermal.empty()) {
    const std::string& d = args.gyro_thermal;
    if (d.size() != 1 || d[0] < '0' || d[0] > '9') {
      throw UsageError("--gyro-thermal: '" + d + "' is neither auto nor a degree from 0 to " +
                       std::to_string(kMaxThermalDegree));
    }
    r->gyro_thermal = d[0] - '0';
  }
  if (args.gyro_model != "auto") {
    r->gyro_model = ParseEnum(GyroModelKindFromString(args.gyro_model), args.gyro_model,
                              "--gyro-model", (NameList<GyroModelKind>() + ", auto").c_str());
  }
}

}  // namespace

UnitRequest CalibrateRequest(const CalibrateArgs& args, Gravity* g) {
  if (args.date_given) {
    if (const auto why = CheckProvenanceDate(args.date)) throw UsageError("--date: " + *why);
  }
  UnitRequest r;
  r.inputs = {args.input.path};
  r.inputs.insert(r.inputs.end(), args.input.more_paths.begin(), args.input.more_paths.end());
  r.load.read = MakeReadOptions(args.input);
  r.load.detection = args.input.detection;
  if (GyroWanted(args)) GyroRequest(args, &r);
  r.orientations = args.orientations;
  r.noise = args.noise;
  r.bias_random_walk = args.bias_random_walk;
  r.temperatures_c = args.temperatures_c;
  r.model = args.model == "auto"
                ? std::nullopt
                : std::optional(ParseEnum(ModelKindFromString(args.model), args.model, "--model",
                                          (NameList<ModelKind>() + ", auto").c_str()));
  if (Given(args, "--method")) {
    r.method = ParseChoice<SolverMethod>(args.method, "--method", kOrientationFreeMethods);
  }
  if (Given(args, "--init")) {
    r.init = ParseChoice<Initialization>(args.init, "--init", kInitializations);
  }
  if (Given(args, "--frame")) r.frame = ParseChoice<Frame>(args.frame, "--frame");
  if (Given(args, "--estimator"))
    r.estimator = ParseChoice<Estimator>(args.estimator, "--estimator");
  if (args.bias_model == "auto") {
    r.bias_model_auto = true;
  } else if (Given(args, "--bias-model")) {
    r.bias_model = BiasModelFromString(args.bias_model);
    if (!r.bias_model) {
      throw UsageError("--bias-model: '" + args.bias_model +
                       "' is none of constant, linear, spline:K (K from 2 to " +
                       std::to_string(kMaxBiasKnots) + ") or auto");
    }
  }
  if (!args.thermal.empty()) {
    r.thermal = true;
    r.thermal_degrees = ParseThermalDegrees(args.thermal);
  }
  r.outliers = ParseOutlierOptions(args.outliers);
  r.cross_validate = args.cross_validate;
  r.max_iterations = args.max_iterations;
  *g = ResolveGravity(args.gravity);
  r.units = g->unit;
  r.gravity_ms2 = g->ms2;
  r.latitude_deg = args.gravity.latitude_deg;
  for (const auto& [name, values] : args.given_options) {
    if (name == "raw-units") r.raw_units = args.raw_units;
  }
  r.provenance.command = "accelcal calibrate";
  r.provenance.options = GivenOptionsJson(args.given_options);
  r.provenance.date = args.date;
  return r;
}

RenderedCalibration RenderCalibration(const UnitOutcome& unit, const std::string& name,
                                      bool report) {
  RenderedCalibration out;
  out.json = CalibrationToJson(unit.accelerometer, unit.FileInfo());
  if (report) {
    ReportInput input;
    input.calibration_name = name;
    input.calibration = ParseCalibrationJson(out.json, input.calibration_name);
    if (const LoadedFile* raw = unit.input.FirstRaw()) {  // the report plots one log: the first
      input.log = &raw->data.raw;
      input.rejected = raw->detection->rejected;
    }
    out.report = RenderReport(input);
  }
  return out;
}

namespace {

// The end of every calibrate: the file to -o, then the file to stdout (--json) or the summary.
int WriteCalibration(const CalibrateArgs& args, const UnitOutcome& unit, const Gravity& g) {
  const CalibrationResult& result = unit.accelerometer;
  const LoadedInput& in = unit.input;
  const Diagnosis& diagnosis = unit.diagnosis;
  // Everything is rendered before anything is written: a failure leaves no file behind.
  const RenderedCalibration rendered = RenderCalibration(
      unit, args.output.empty() ? args.input.path : args.output, !args.report.empty());
  const std::string& json = rendered.json;
  const std::string& report = rendered.report;
  {  // both files or neither
    std::optional<OutputFile> file, report_file;
    if (!args.output.empty()) file.emplace(args.output).Write(json);
    if (!args.report.empty()) report_file.emplace(args.report).Write(report);
    CommitAll({file ? &*file : nullptr, report_file ? &*report_file : nullptr});
  }
  const char* force_unit = g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g";
  const std::vector<double> errors = GravityNormErrors(result, Means(in.positions));
  for (const OutlierFinding& o : result.outliers) {
    Warn("%s: %s%s\n", args.input.path.c_str(),
         OutlierMessage(o, in.positions, errors, force_unit, in.position_file).c_str(),
         o.excluded ? " It was left out of the fit." : " It was kept in the fit.");
  }
  PrintFindings(diagnosis, args.input.path,
                unit.gyroscope ? unit.gyroscope->calibration.source : args.input.path);
  if (args.json) {
    WriteFileAtomically("-", json);
  } else {
    PrintInput(in);
    std::stringstream notes(WithCliFlags(unit.notes));
    for (std::string line; std::getline(notes, line);) Say("%s\n", Shown(line).c_str());
    PrintCalibration(result, in.positions, in.position_file, g, unit.raw_unit);
    if (result.thermal) {
      Say("%s", ThermalText(result, unit.thermal_selection ? &*unit.thermal_selection : nullptr, g,
                            unit.raw_unit)
                    .c_str());
    }
    if (unit.model_selection) PrintModelSelection(*unit.model_selection, args.model == "auto");
    if (const std::optional<BiasModelSelection>& b = unit.bias_model_selection) {
      Say("bias      auto -> %s: %s\n", ToString(b->chosen).c_str(), b->reason.c_str());
    }
    if (unit.gyroscope) PrintGyro(*unit.gyroscope, force_unit);
    for (const Finding& f : diagnosis.findings) {
      // A note's option, where it suggests one (the summary's other notes name none).
      const char* hint = f.code == "temperature_span" ? OptionHint(f) : "";
      if (f.severity == Severity::kNote) Say("note      %s%s\n", f.message.c_str(), hint);
    }
    Say("verdict   %s\n", std::string(ToString(diagnosis.verdict())).c_str());
    if (!args.output.empty()) Say("wrote     %s\n", Shown(args.output).c_str());
    if (!args.report.empty()) Say("report    %s\n", Shown(args.report).c_str());
  }
  if (diagnosis.verdict() == Verdict::kFailed) {
    WriteErrLine(
        Format("accelcal: %s: the calibration failed its checks: written, but marked "
               "\"verdict\": \"failed\"; do not use it as it is\n",
               args.input.path.c_str()));
    return kExitFailedChecks;
  }
  return kExitOk;
}

}  // namespace

int RunCalibrate(const CalibrateArgs& args) {
  {
    std::vector<std::string> inputs = args.input.more_paths;
    inputs.push_back(args.input.path);
    inputs.push_back(args.orientations);
    inputs.push_back(args.gyro.log);
    inputs.push_back(args.noise);
    CheckOutputs({{"-o", args.output}, {"--report", args.report}}, inputs);
  }
  Gravity g{};
  UnitRequest request = CalibrateRequest(args, &g);
  ReportLoading(&request.load);
  const UnitOutcome unit = CalibrateUnit(request);
  if (!unit.converged()) {
    WriteErrLine("accelcal: " + DidNotConverge(args.input.path, unit) + "\n");
    return kExitNotConverged;
  }
  return WriteCalibration(args, unit, g);
}

CommandRun SetUpCalibrate(CLI::App* cmd, const CalibrateRunner& runner) {
  auto a = std::make_shared<CalibrateArgs>();
  auto inputs = std::make_shared<std::vector<std::string>>();
  cmd->add_option("INPUT", *inputs,
                  "raw logs or positions files (several: sessions of one device, positions "
                  "pooled; - reads standard input)")
      ->required();
  AddCalibrationOptions(cmd, a.get());
  cmd->add_option("-o,--output", a->output, "write the calibration file (JSON) here")
      ->check(kFileName);
  cmd->add_option("--report", a->report,
                  "write the HTML report here (self-contained: plots, parameters, warnings)")
      ->check(kFileName);
  AddDateOption(cmd, a.get());
  cmd->add_flag("--json", a->json, "print the calibration file to stdout instead of the summary");
  return [a, inputs, runner](const CLI::App& parsed) {
    if (!inputs->empty()) {  // INPUT is required: the parse has refused none
      a->input.path = inputs->front();
      a->input.more_paths.assign(inputs->begin() + 1, inputs->end());
    }
    DataSubject() = a->input.path;
    CheckCalibrationFlags(parsed, a.get());
    a->given_options = GivenOptions(parsed, {"output", "report", "json", "date"});
    return runner ? runner(*a) : RunCalibrate(*a);
  };
}

}  // namespace accelcal::cli
