// Paper 003's commands: system-level and gimbal.
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

#include "accelcal/calibration_file.hpp"
#include "accelcal/compare.hpp"
#include "accelcal/design.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/engineering.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/gimbal_platform.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/known_orientation.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/montecarlo.hpp"
#include "accelcal/orientation_file.hpp"
#include "accelcal/report.hpp"
#include "accelcal/series_file.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/system_level.hpp"
#include "accelcal/table_file.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {
int RunSystemLevel(const SystemLevelArgs& args) {
  const double latitude = *args.latitude_deg;
  if (!(std::abs(latitude) < 89)) throw UsageError("--latitude must lie in (-89, 89) degrees");
  if (std::abs(latitude) < 1) {
    throw UsageError(
        "--latitude: within 1 degree of the equator sin L vanishes and the second "
        "harmonics of the attitude errors carry no information (eq. (32), (33))");
  }
  const double g = args.gravity_ms2 ? *args.gravity_ms2 : NormalGravityWgs84_ms2(latitude);
  if (!(g > 0) || !std::isfinite(g)) throw UsageError("--gravity must be a positive number");
  SystemLevelOptions options;
  options.latitude_rad = latitude * 3.14159265358979323846 / 180.0;
  options.gravity_ms2 = g;
  if (const auto error = options.Validate()) throw UsageError(*error);
  SystemLevelEstimator estimator(options);
  ProgressBar bar("system-level");
  ReadSeries(
      args.series, [&](const SystemSample& s) { estimator.Add(s); }, bar.ByteCallback());
  bar.Finish();
  const SystemLevelResult r = estimator.Finish();
  Detail("system-level: %s\n", r.summary.termination_message.c_str());
  const auto fourier = [](const FourierCoefficients& f) {
    return nlohmann::ordered_json{
        {"mean", f.mean}, {"c1", f.c1}, {"s1", f.s1}, {"c2", f.c2}, {"s2", f.s2}};
  };
  std::string out;
  if (args.json) {
    nlohmann::ordered_json doc;
    doc["samples"] = r.samples;
    doc["latitude_deg"] = latitude;
    doc["gravity_ms2"] = g;
    doc["noise_ms2"] = JsonArray(r.noise_ms2);
    doc["x1_noise_correction"] = r.x1_noise_correction;
    nlohmann::ordered_json combined = nlohmann::ordered_json::object();
    for (int i = 0; i < 5; ++i) {
      combined["x" + std::to_string(i + 1)] = {{"value", r.x(i)}, {"std", r.x_std(i)}};
    }
    doc["combined"] = combined;
    doc["fourier"] = {{"pitch", fourier(r.pitch)},
                      {"pitch_std", fourier(r.pitch_std)},
                      {"roll", fourier(r.roll)},
                      {"roll_std", fourier(r.roll_std)}};
    nlohmann::ordered_json determined = nlohmann::ordered_json::object();
    for (const Estimate& e : r.determined)
      determined[e.name] = {{"value", e.value}, {"std", e.std}};
    doc["separated"] = {
        {"rank", r.rank}, {"determined", determined}, {"undetermined", r.undetermined}};
    out = JsonText(doc);
  } else {
    out += Format("system-level  %s: %ld samples, latitude %.6g deg, g %.9g m/s2\n",
                  args.series.c_str(), r.samples, latitude, g);
    out += Format(
        "noise         %.3g %.3g %.3g m/s2 per axis (successive differences); x1 "
        "corrected by E|n|^2/(2g^2) = %.3g\n",
        r.noise_ms2(0), r.noise_ms2(1), r.noise_ms2(2), r.x1_noise_correction);
    out += "combined coefficients, eq. (21)-(25) [rad]\n";
    for (int i = 0; i < 5; ++i) {
      out += Format("  x%d  %+.5e +- %.2e\n", i + 1, r.x(i), r.x_std(i));
    }
    const auto line = [](const char* name, const FourierCoefficients& f,
                         const FourierCoefficients& sd) {
      return Format(
          "  %-5s mean %+.4e +- %.1e  c1 %+.4e +- %.1e  s1 %+.4e +- %.1e  c2 %+.4e +- "
          "%.1e  s2 %+.4e +- %.1e\n",
          name, f.mean, sd.mean, f.c1, sd.c1, f.s1, sd.s1, f.c2, sd.c2, f.s2, sd.s2);
    };
    out += "attitude errors, Fourier coefficients of S = Earth rate x t [rad]\n";
    out += line("pitch", r.pitch, r.pitch_std) + line("roll", r.roll, r.roll_std);
    out += Format("separated, eq. (39)-(41) (rank %d of 6)\n", r.rank);
    for (const Estimate& e : r.determined) {
      out += Format("  %-34s %+.5e +- %.2e\n", e.name.c_str(), e.value, e.std);
    }
    if (!r.undetermined.empty()) {
      std::string names;
      for (const std::string& n : r.undetermined) names += (names.empty() ? "" : ", ") + n;
      out += "  not determined on their own (only in the combinations above): " + names + "\n";
    }
  }
  WriteFileAtomically("-", out);
  return kExitOk;
}

namespace {

nlohmann::ordered_json DeviceJson(const PlatformAccelerometer& d) {
  static const char* const kNames[6] = {"beta_xz", "beta_xy", "beta_yz",
                                        "beta_yx", "beta_zy", "beta_zx"};
  nlohmann::ordered_json beta;
  for (int i = 0; i < 6; ++i) beta[kNames[i]] = d.beta(i);
  return {{"sf_inverse", JsonArray(d.s)},
          {"bias", JsonArray(d.bias)},
          {"beta_rad", beta},
          {"k_nl", JsonArray(d.k_nl)}};
}

std::vector<double> Values(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

}  // namespace

int RunGimbal(const GimbalArgs& args) {
  const Gravity g = ResolveGravity(args.gravity);
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  std::vector<Vec3> commanded, outputs;
  for (const std::vector<double>& row : ReadNumberTable(args.coarse, 6)) {
    commanded.emplace_back(row[0] * kDeg, row[1] * kDeg, row[2] * kDeg);
    outputs.emplace_back(row[3], row[4], row[5]);
  }
  CoarseCalibrationOptions coarse_options;
  coarse_options.gravity = g.in_unit;
  const CoarseCalibrationResult coarse = CoarseCalibration(outputs, commanded, coarse_options);
  Detail("gimbal coarse: %s\n", coarse.summary.BriefReport().c_str());
  std::optional<FineCalibrationResult> fine;
  if (!args.fine.empty()) {
    std::vector<Vec3> fine_outputs;
    for (const std::vector<double>& row : ReadNumberTable(args.fine, 3)) {
      fine_outputs.emplace_back(row[0], row[1], row[2]);
    }
    FineCalibrationOptions fine_options;
    fine_options.gravity = g.in_unit;
    fine = FineCalibration(fine_outputs, coarse.device, fine_options);
    Detail("gimbal fine: %s\n", fine->summary.BriefReport().c_str());
  }
  std::string out;
  if (args.json) {
    nlohmann::ordered_json doc;
    doc["gravity"] = g.in_unit;
    doc["coarse"] = {
        {"device", DeviceJson(coarse.device)},
        {"offsets_rad", {{"theta20", coarse.offsets(1)}, {"theta30", coarse.offsets(2)}}},
        {"std", Values(coarse.std)},
        {"parameter_order",
         {"s_x", "s_y", "s_z", "b_x", "b_y", "b_z", "beta_xz", "beta_xy", "beta_yz", "beta_yx",
          "beta_zy", "beta_zx", "theta20", "theta30"}},
        {"residual_rms", coarse.residual_rms},
        {"converged", coarse.summary.converged()},
        {"note", coarse.note}};
    if (fine) {
      doc["fine"] = {{"device", DeviceJson(fine->device)},     {"dx", Values(fine->dx)},
                     {"dx_std", Values(fine->dx_std)},         {"residual_rms", fine->residual_rms},
                     {"converged", fine->summary.converged()}, {"note", fine->note}};
    }
    out = JsonText(doc);
  } else {
    const auto device = [&](const PlatformAccelerometer& d) {
      std::string text = Format("  SF^-1   %.10g %.10g %.10g\n", d.s(0), d.s(1), d.s(2));
      text += Format("  bias    %.6g %.6g %.6g\n", d.bias(0), d.bias(1), d.bias(2));
      text += Format("  beta    xz %.2f  xy %.2f  yz %.2f  yx %.2f  zy %.2f  zx %.2f arcsec\n",
                     d.beta(0) / kDeg * 3600, d.beta(1) / kDeg * 3600, d.beta(2) / kDeg * 3600,
                     d.beta(3) / kDeg * 3600, d.beta(4) / kDeg * 3600, d.beta(5) / kDeg * 3600);
      return text;
    };
    out += Format("coarse    %zu positions, %s after %d iterations, residual rms %.3g\n",
                  outputs.size(), coarse.summary.converged() ? "converged" : "NOT CONVERGED",
                  coarse.summary.iterations, coarse.residual_rms);
    out += device(coarse.device);
    out += Format("  offsets theta20 %.2f +- %.2f arcsec, theta30 %.2f +- %.2f arcsec\n",
                  coarse.offsets(1) / kDeg * 3600, coarse.std(12) / kDeg * 3600,
                  coarse.offsets(2) / kDeg * 3600, coarse.std(13) / kDeg * 3600);
    out += "  note    " + coarse.note + "\n";
    if (fine) {
      out += Format("fine      %s after %d iterations, residual rms %.3g\n",
                    fine->summary.converged() ? "converged" : "NOT CONVERGED",
                    fine->summary.iterations, fine->residual_rms);
      out += device(fine->device);
      out += Format("  K_nl    %.4g %.4g %.4g per output unit\n", fine->device.k_nl(0),
                    fine->device.k_nl(1), fine->device.k_nl(2));
      out += "  note    " + fine->note + "\n";
    }
  }
  WriteFileAtomically("-", out);
  const bool ok = coarse.summary.converged() && (!fine || fine->summary.converged());
  return ok ? kExitOk : kExitNotConverged;
}

CommandRun SetUpSystemLevel(CLI::App* cmd) {
  auto a = std::make_shared<SystemLevelArgs>();
  cmd->add_option("SERIES", a->series, "series file (binary or t,fx,fy,fz,roll,pitch)")->required();
  cmd->add_option("--latitude", a->latitude_deg, "latitude of the base [deg]")->required();
  cmd->add_option("--gravity", a->gravity_ms2,
                  "local gravity [m/s2] (default: WGS-84 normal gravity)");
  cmd->add_flag("--json", a->json, "machine-readable output");
  return [a](const CLI::App& /*parsed*/) {
    DataSubject() = a->series;
    return RunSystemLevel(*a);
  };
}

CommandRun SetUpGimbal(CLI::App* cmd) {
  auto a = std::make_shared<GimbalArgs>();
  cmd->add_option("COARSE", a->coarse,
                  "commanded gimbal angles and mean output per position: "
                  "theta1_deg,theta2_deg,theta3_deg,ax,ay,az (Table 1's 18 positions)")
      ->required();
  cmd->add_option("--fine", a->fine,
                  "mean outputs ax,ay,az of the fine stage's positions, measured after "
                  "re-zeroing the gimbals by the coarse offsets");
  AddGravityOptions(cmd, &a->gravity);
  cmd->add_flag("--json", a->json, "machine-readable output");
  return [a](const CLI::App& /*parsed*/) {
    DataSubject() = a->coarse;
    return RunGimbal(*a);
  };
}

}  // namespace accelcal::cli
