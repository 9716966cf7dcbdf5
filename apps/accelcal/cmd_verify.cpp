// accelcal verify: a calibration applied to a new recording of the same unit, each still
// position's |f| - g against the error the calibration predicts (verify.hpp).
#include "commands.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/verify.hpp"
#include "cli_common.hpp"
#include "core/text_format.hpp"
#include "output.hpp"

namespace accelcal::cli {

using internal::Format;
using internal::VisibleLine;

namespace {

// What the calibration's own positions scattered by beyond their noise [raw]: its residual σ̂
// less the mean noise of its position means (σ²/n per axis: white samples; a filtered sensor's
// are noisier, which leaves this larger and the test more lenient). All of σ̂ when its positions
// carry no noise; 0 when the file has no σ̂.
double MisfitSigma(const LoadedCalibration& cal) {
  if (!cal.noise_sigma_raw) return 0;
  double sum = 0;
  std::size_t count = 0;
  for (const FilePosition& p : cal.positions) {
    if (p.excluded || !p.std || !p.samples || *p.samples == 0) continue;
    sum += p.std->squaredNorm() / 3 / static_cast<double>(*p.samples);
    ++count;
  }
  const double noise2 = count > 0 ? sum / static_cast<double>(count) : 0.0;
  return std::sqrt(std::max(0.0, *cal.noise_sigma_raw * *cal.noise_sigma_raw - noise2));
}

// A number, or null where there is none (a reading the model cannot invert).
nlohmann::ordered_json NumberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

}  // namespace

int RunVerify(const VerifyArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration, args.input.path});
  if (auto why = args.input.detection.Validate()) throw UsageError(*why);
  const LoadedCalibration cal = ParseCalibrationJson(
      ReadFileToString(args.calibration, kMaxSmallFileBytes), args.calibration);
  RefuseFailed(cal, args.calibration);
  VerifiedCalibration under_test;
  under_test.model = cal.model;
  under_test.frame = cal.frame;
  under_test.params = cal.params;
  under_test.covariance = cal.covariance;
  under_test.gravity = cal.gravity;
  under_test.misfit_sigma_raw = MisfitSigma(cal);
  std::string gravity_origin = "the calibration's";
  if (args.gravity.gravity_ms2 || args.gravity.latitude_deg) {
    GravityArgs site = args.gravity;
    site.units = std::string(ToString(cal.unit));
    const Gravity g = ResolveGravity(site);
    under_test.gravity = g.in_unit;
    gravity_origin = g.origin;
  }
  ReadOptions read = MakeReadOptions(args.input);
  read.kind = InputKind::kRaw;
  const InputData data = ReadInput(args.input.path, read);
  const StaticDetectionResult detection = DetectStaticIntervals(data.raw, args.input.detection);
  if (detection.intervals.empty()) throw NoStaticInterval(detection);
  const std::vector<Position> positions = PositionsFromIntervals(detection.intervals);
  const Verification v = VerifyCalibration(under_test, data.raw, positions);

  const std::string unit(ToString(cal.unit));
  std::string out;
  if (args.json) {
    nlohmann::ordered_json doc;
    doc["calibration"] = args.calibration;
    doc["log"] = args.input.path;
    doc["unit"] = unit;
    doc["gravity"] = under_test.gravity;
    doc["gravity_origin"] = gravity_origin;
    doc["misfit_sigma_raw"] = under_test.misfit_sigma_raw;
    doc["verdict"] = v.passed ? "passed" : "failed";
    if (!v.passed) doc["reason"] = v.reason;
    doc["chi2"] = v.chi2;
    doc["dof"] = v.dof;
    doc["p_value"] = v.p_value;
    doc["significance"] = VerifyOptions().significance;
    doc["rms_error"] = v.rms_error;
    doc["rms_predicted"] = v.rms_predicted;
    nlohmann::ordered_json off = nlohmann::ordered_json::array();
    for (const std::size_t k : v.off_positions) off.push_back(k + 1);
    doc["off_positions"] = off;
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < v.positions.size(); ++k) {
      const VerifiedPosition& p = v.positions[k];
      list.push_back({{"position", k + 1},
                      {"t_begin_s", p.t_begin_s},
                      {"t_end_s", p.t_end_s},
                      {"samples", p.samples},
                      {"mean_raw", {p.mean_raw(0), p.mean_raw(1), p.mean_raw(2)}},
                      {"error", NumberOrNull(p.error)},
                      {"sigma", NumberOrNull(p.sigma)},
                      {"sigma_parameters", p.sigma_parameters},
                      {"sigma_noise", p.sigma_noise},
                      {"sigma_misfit", p.sigma_misfit},
                      {"z", NumberOrNull(p.z)}});
    }
    doc["positions"] = list;
    doc["gyroscope"] = cal.has_gyroscope()
                           ? "not verified: this verification is the accelerometer's"
                           : "none in the calibration";
    out = JsonText(doc);
  } else {
    out += "# accelcal verify " + VisibleLine(args.calibration) + " on " +
           VisibleLine(args.input.path) + ": " + std::to_string(v.positions.size()) +
           " still positions\n";
    out += Format(
        "# |f| - g [%s] against the error the calibration predicts: its parameters' "
        "covariance, each position's noise, its own misfit (%.3g raw); g = %.9g %s (%s)\n",
        unit.c_str(), under_test.misfit_sigma_raw, under_test.gravity, unit.c_str(),
        gravity_origin.c_str());
    out += "position  t_begin_s  t_end_s  samples  error  sigma  z\n";
    for (std::size_t k = 0; k < v.positions.size(); ++k) {
      const VerifiedPosition& p = v.positions[k];
      out += Format("%zu  %.3f  %.3f  %zu  %.4g  %.3g  %+.2f\n", k + 1, p.t_begin_s, p.t_end_s,
                    p.samples, p.error, p.sigma, p.z);
    }
    out += Format(
        "# chi2 = %.4g for %d positions (p = %.3g); RMS of |f| - g %.3g %s, predicted %.3g %s\n",
        v.chi2, v.dof, v.p_value, v.rms_error, unit.c_str(), v.rms_predicted, unit.c_str());
    if (cal.has_gyroscope()) {
      out += "# the gyroscope: not verified (this verification is the accelerometer's)\n";
    }
    out += v.passed ? std::string("# verdict: passed\n") : "# verdict: failed: " + v.reason + "\n";
  }
  WriteFileAtomically(args.output.empty() ? "-" : args.output, out);
  if (!v.passed) {
    Warn("%s does not hold on %s: %s\n", args.calibration.c_str(), args.input.path.c_str(),
         v.reason.c_str());
    return kExitFailedChecks;
  }
  return kExitOk;
}

}  // namespace accelcal::cli
