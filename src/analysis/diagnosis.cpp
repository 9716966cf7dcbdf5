#include "accelcal/diagnosis.hpp"

#include <algorithm>
#include <cmath>

#include "accelcal/engineering.hpp"
#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/noise.hpp"
#include "analysis/findings.hpp"
#include "core/median.hpp"
#include "core/text_format.hpp"
#include "statistics/student_t.hpp"

namespace accelcal {

using internal::Format;

std::string_view ToString(Severity severity) { return NameOf(severity); }

std::string_view ToString(Verdict verdict) { return NameOf(verdict); }

Verdict Diagnosis::verdict() const {
  Verdict v = Verdict::kOk;
  for (const Finding& f : findings) {
    if (f.severity == Severity::kFailure) return Verdict::kFailed;
    if (f.severity == Severity::kWarning) v = Verdict::kWarnings;
  }
  return v;
}

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr const char* kAxisName[3] = {"x", "y", "z"};

// Largest angle [deg] from any direction to the nearest of `directions`, on a Fibonacci grid of
// 2000 points, and where.
std::pair<double, Vec3> LargestGap(const std::vector<Vec3>& directions) {
  std::vector<Vec3> unit;  // normalised once, not once per grid point
  unit.reserve(directions.size());
  for (const Vec3& d : directions) unit.push_back(d.normalized());
  double worst = 0;
  Vec3 where = Vec3::UnitZ();
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double phi = i * kPi * (3.0 - std::sqrt(5.0));
    const Vec3 u(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
    double closest = -1;  // the largest cosine is the nearest direction: one acos per point
    for (const Vec3& d : unit) closest = std::max(closest, u.dot(d));
    const double nearest = std::acos(std::clamp(closest, -1.0, 1.0));
    if (nearest > worst) worst = nearest, where = u;
  }
  return {worst * 180.0 / kPi, where};
}

using internal::AddFinding;
using internal::Median;

// RMS misfit as a fraction of g (see the file comment), over the positions in the fit.
double MisfitFraction(const CalibrationResult& r, const std::vector<Vec3>& means) {
  if (r.frame == Frame::kPlatform) {
    const Mat33 K_inv = r.params.K.inverse();
    double sum = 0;
    int m = 0;
    for (std::size_t k = 0; k < r.residuals.size(); ++k) {
      if (r.excluded(k)) continue;
      sum += (K_inv * r.residuals[k]).squaredNorm();
      ++m;
    }
    return m > 0 ? std::sqrt(sum / m) / r.gravity : 0.0;
  }
  return Rms(r.InFit(GravityNormErrors(r, means))) / r.gravity;
}

void PoorlyDetermined(const CalibrationResult& r, std::vector<Finding>* out) {
  if (r.covariance.size() == 0) return;
  const EngineeringStd s =
      EngineeringUncertainty(r.params, r.model, r.frame, r.gravity, r.covariance);
  const EngineeringParameters eng = ToEngineering(r.params, r.gravity);
  const Misalignment mis = MisalignmentOf(r.params.K, r.frame);
  std::string list;
  std::vector<std::pair<std::string, double>> numbers;
  const auto poorly = [&](const std::string& what, double sigma, double limit, const char* unit) {
    list += Format("%s%s (1 sigma %.3g %s, beyond %.3g)", list.empty() ? "" : ", ", what.c_str(),
                   sigma, unit, limit);
    numbers.push_back({what, sigma});
  };
  for (int i = 0; i < 3; ++i) {
    const double relative = 100 * s.scale_factor(i) / std::abs(eng.scale_factor(i));
    if (relative > 1.0) poorly(std::string("scale factor ") + kAxisName[i], relative, 1.0, "%");
  }
  for (Eigen::Index i = 0; i < s.misalignment_rad.size(); ++i) {
    const double deg = s.misalignment_rad(i) * 180 / kPi;
    if (deg > 0.5) {
      poorly("misalignment " + std::string(mis.names[static_cast<std::size_t>(i)]), deg, 0.5,
             "deg");
    }
  }
  for (int i = 0; i < 3; ++i) {
    const double mg = 1e3 * s.bias_force(i) / r.gravity;
    if (mg > 10) poorly(std::string("bias ") + kAxisName[i], mg, 10, "mg");
    if (r.model == ModelKind::kQuadratic && s.k2_g_per_g2(i) > 0.01) {
      poorly(std::string("squared coefficient ") + kAxisName[i], s.k2_g_per_g2(i), 0.01, "g/g^2");
    }
  }
  if (!list.empty()) {
    AddFinding(out, "poorly_determined", Severity::kWarning,
               "poorly determined: " + list + "; add positions that excite them", numbers);
  }
}

// The lag-1 autocorrelation of the samples about their mean, pooled over the axes, of each still
// interval; the median over the intervals. White noise gives 0, samples repeated in pairs +0.5
// (the T265), two sensors whose rows alternate −1: each step jumps between them.
double MedianLagOneCorrelation(const RawLog& log, const std::vector<StaticInterval>& intervals) {
  std::vector<double> rho;
  for (const StaticInterval& s : intervals) {
    double num = 0, den = 0;
    for (std::size_t i = s.begin; i < s.end; ++i) {
      const Vec3 d = log.samples[i] - s.mean;
      den += d.squaredNorm();
      if (i + 1 < s.end) num += d.dot(log.samples[i + 1] - s.mean);
    }
    if (den > 0) rho.push_back(num / den);
  }
  return rho.empty() ? 0.0 : Median(rho);
}

}  // namespace

std::vector<Finding> TimeFindings(const TimeAxis& time) {
  std::vector<Finding> out;
  AddFinding(
      &out, "time_unit", Severity::kNote,
      Format("time in %s: %s; times are seconds from the first sample (t = %.15g s)",
             std::string(ToString(time.unit)).c_str(), time.unit_reason.c_str(), time.origin_s),
      {{"origin_s", time.origin_s}, {"rate_hz", time.rate_hz}});
  if (!time.gaps.empty()) {
    const auto longest = std::max_element(
        time.gaps.begin(), time.gaps.end(), [](const TimeGap& a, const TimeGap& b) {
          return a.t_after_s - a.t_before_s < b.t_after_s - b.t_before_s;
        });
    AddFinding(
        &out, "time_gaps", Severity::kNote,
        Format("the time column has %zu gap%s (steps over %.0f times the typical %.4g s; the "
               "longest %.4g s at %.4g s): the %zu pieces are detected separately and no interval "
               "spans a gap",
               time.gaps.size(), time.gaps.size() == 1 ? "" : "s", kGapFactor, time.typical_step_s,
               longest->t_after_s - longest->t_before_s, longest->t_before_s, time.gaps.size() + 1),
        {{"gaps", static_cast<double>(time.gaps.size())},
         {"longest_s", longest->t_after_s - longest->t_before_s}});
  }
  if (time.repeated_fraction > 0.05) {
    AddFinding(
        &out, "coarse_timestamps", Severity::kNote,
        Format("%.0f %% of the time steps are 0: the timestamps (resolution %.4g s) are coarser "
               "than the sample period; the rate is taken over spans (%.6g Hz)",
               100 * time.repeated_fraction, time.resolution_s, time.rate_hz),
        {{"repeated_fraction", time.repeated_fraction}, {"resolution_s", time.resolution_s}});
  }
  if (time.irregular_fraction > 0.01) {
    AddFinding(
        &out, "irregular_sampling",
        time.irregular_fraction > 0.1 ? Severity::kWarning : Severity::kNote,
        Format("irregular sampling: %.1f %% of the time steps differ from the typical %.4g s by "
               "more than half of it",
               100 * time.irregular_fraction, time.typical_step_s),
        {{"irregular_fraction", time.irregular_fraction}});
  }
  return out;
}

// A bias that drifts within the longest still interval (the rest a calibration log starts with):
// its Allan deviation rises with averaging time, which the noise fit (noise_model.hpp) resolves
// as bias instability, random walk or rate ramp at kDriftZ standard errors or more. Then the
// positions' means carry the drift, which no constant bias explains (the T265 shows it within
// its 50-second rest). Only an interval of kDriftMinRest_s or more, less a detection window at
// each end (its edges are blurred, as `accelcal noise --still` takes it).
std::optional<Finding> DriftFinding(const RawLog& log, const StaticDetectionResult& detection) {
  const StaticInterval* longest = nullptr;
  for (const StaticInterval& s : detection.intervals) {
    if (s.averaged == 0 && (!longest || s.count() > longest->count())) longest = &s;
  }
  if (!longest || !(detection.rate_hz > 0)) return std::nullopt;
  std::size_t begin = longest->begin, end = longest->end;
  if (end - begin > 4 * detection.window_samples) {
    begin += detection.window_samples;
    end -= detection.window_samples;
  }
  const double seconds = static_cast<double>(end - begin) / detection.rate_hz;
  if (seconds < kDriftMinRest_s) return std::nullopt;
  NoiseAnalysis noise;
  try {
    NoiseOptions options;
    options.fit.intervals = false;  // the terms' z alone are looked at
    noise = AnalyseNoise(std::vector<Vec3>(log.samples.begin() + static_cast<std::ptrdiff_t>(begin),
                                           log.samples.begin() + static_cast<std::ptrdiff_t>(end)),
                         1 / detection.rate_hz, options);
  } catch (const DataError&) {
    return std::nullopt;  // a constant (quantised) axis: nothing to see
  }
  std::string seen;
  double largest_z = 0;
  // A steady drift (a warm-up) first: the slope of the rest's kDriftBatches batch means against
  // their times, its t with kDriftBatches − 2 degrees of freedom (the batches' scatter holds the
  // samples' correlation), two-sided at kDriftP over the three axes (Bonferroni). A steady
  // drift makes the Allan deviation rise as τ (rate ramp), but the fit sees that only in its
  // last octaves, of a few degrees of freedom: a drift of 24 mg in the Xsens rest's 52 s
  // resolved as rate ramp at 2.5 σ only.
  {
    const std::size_t n = end - begin, size = n / kDriftBatches;
    const double t_limit = internal::StudentTTwoSidedQuantile(kDriftP / 3, kDriftBatches - 2.0);
    for (int a = 0; a < 3 && size >= 2; ++a) {
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      std::vector<double> means;
      for (std::size_t b = 0; b < kDriftBatches; ++b) {
        double m = 0;
        for (std::size_t i = 0; i < size; ++i) m += log.samples[begin + b * size + i](a);
        m /= static_cast<double>(size);
        const double x = static_cast<double>(b);
        sx += x, sy += m, sxx += x * x, sxy += x * m;
        means.push_back(m);
      }
      const auto B = static_cast<double>(kDriftBatches);
      const double slope = (sxy - sx * sy / B) / (sxx - sx * sx / B);
      const double intercept = (sy - slope * sx) / B;
      double rss = 0;
      for (std::size_t b = 0; b < kDriftBatches; ++b) {
        rss += std::pow(means[b] - intercept - slope * static_cast<double>(b), 2);
      }
      const double se = std::sqrt(rss / (B - 2) / (sxx - sx * sx / B));
      const double t = se > 0 ? slope / se : 0.0;
      if (!(std::abs(t) > t_limit)) continue;
      const double per_minute = slope / (static_cast<double>(size) / detection.rate_hz) * 60;
      seen += Format("%s%c drifts %+.3g raw per minute (t = %.1f)", seen.empty() ? "" : ", ",
                     "xyz"[a], per_minute, t);
      largest_z = std::max(largest_z, std::abs(t));
    }
  }
  for (int a = 0; a < 3; ++a) {
    for (const NoiseTerm t :
         {NoiseTerm::kBiasInstability, NoiseTerm::kRandomWalk, NoiseTerm::kRateRamp}) {
      const NoiseTermEstimate& e = noise.axes[std::size_t(a)].fit.terms[std::size_t(t)];
      if (!e.resolved || !(e.z >= kDriftZ)) continue;
      seen += Format("%s%c %s (%.1f sigma)", seen.empty() ? "" : ", ", "xyz"[a],
                     std::string(ToString(t)).c_str(), e.z);
      largest_z = std::max(largest_z, e.z);
    }
  }
  if (seen.empty()) return std::nullopt;
  return Finding{"drifting_rest",
                 Severity::kWarning,
                 Format("the longest still interval (samples %zu-%zu, %.0f s) has an Allan "
                        "deviation that rises with averaging time: %s: its bias drifts, and the "
                        "positions' means carry the drift, which a constant bias does not "
                        "explain (the held-out error shows its cost)",
                        begin + 1, end, seconds, seen.c_str()),
                 {{"seconds", seconds}, {"largest_statistic", largest_z}}};
}

std::vector<Finding> LogFindings(const RawLog* log, const StaticDetectionResult* detection) {
  std::vector<Finding> out;
  if (log && !log->read_warning.empty()) {
    AddFinding(&out, "log_cut_short", Severity::kWarning,
               log->read_warning + ": those were used; the rest of the recording, if any, is lost",
               {});
  }
  if (log && !log->temperature_note.empty()) {
    AddFinding(&out, "temperature_left_out", Severity::kNote, log->temperature_note, {});
  }
  if (log && detection) {
    if (std::optional<Finding> drift = DriftFinding(*log, *detection)) {
      out.push_back(std::move(*drift));
    }
  }
  if (log && detection && !detection->intervals.empty()) {
    const double rho = MedianLagOneCorrelation(*log, detection->intervals);
    if (rho < kInterleavedCorrelation) {
      AddFinding(
          &out, "interleaved", Severity::kFailure,
          Format("successive samples alternate in the still intervals (lag-1 correlation %.2f, "
                 "below %.1f): the rows come from two sensors in turn; read one of them",
                 rho, kInterleavedCorrelation),
          {{"lag1_correlation", rho}, {"limit", kInterleavedCorrelation}});
    }
  }
  if (log && detection && !detection->corrupted.empty()) {
    const std::size_t i = detection->corrupted.front();
    const Vec3& x = log->samples[i];
    const std::size_t count = detection->corrupted.size();
    AddFinding(
        &out, "corrupted_reading", Severity::kWarning,
        Format(
            "%zu reading%s lie%s more than a million times the log's spread from its median (the "
            "first: sample %zu%s, %.6g %.6g %.6g): corrupted, not a sensor's; left out, and a "
            "still interval around one ends at it",
            count, count == 1 ? "" : "s", count == 1 ? "s" : "", i + 1,
            log->time_s.size() > i ? Format(" at %.6g s", log->time_s[i]).c_str() : "", x(0), x(1),
            x(2)),
        {{"count", static_cast<double>(count)}, {"first_sample", static_cast<double>(i + 1)}});
  }
  if (detection) {
    for (Finding& f : RejectedPeriodFindings(detection->rejected)) out.push_back(std::move(f));
    if (detection->joined > 0) {
      AddFinding(
          &out, "joined_periods", Severity::kNote,
          Format("%zu still period%s split by a short disturbance %s joined (the same orientation "
                 "on both sides, within 5 standard errors)",
                 detection->joined, detection->joined == 1 ? "" : "s",
                 detection->joined == 1 ? "was" : "were"),
          {{"joined", static_cast<double>(detection->joined)}});
    }
  }
  if (log && log->time) {
    for (Finding& f : TimeFindings(*log->time)) out.push_back(std::move(f));
  }
  return out;
}

std::vector<Finding> RejectedPeriodFindings(const std::vector<RejectedInterval>& rejected) {
  std::vector<Finding> out;
  for (const RejectedInterval& r : rejected) {
    AddFinding(&out, "rejected_period",
               r.cause == RejectedInterval::Cause::kClipped ? Severity::kWarning : Severity::kNote,
               Format("the still period %.3f-%.3f s is not used: %s", r.t_begin_s, r.t_end_s,
                      r.reason.c_str()),
               {{"t_begin_s", r.t_begin_s}, {"t_end_s", r.t_end_s}});
  }
  return out;
}

namespace {

// Positions that look like a raw log's samples, each read as a position.
void InputShapeFindings(const DiagnosisInput& input, const std::vector<Vec3>& means,
                        std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  if (input.positions_by_row_count && means.size() >= 3) {
    Vec3 centre = Vec3::Zero();
    for (const Vec3& m : means) centre += m;
    centre /= static_cast<double>(means.size());
    double spread2 = 0;
    for (const Vec3& m : means) spread2 += (m - centre).squaredNorm();
    const double spread = std::sqrt(spread2 / static_cast<double>(means.size()));
    std::vector<double> steps;
    for (std::size_t k = 1; k < means.size(); ++k)
      steps.push_back((means[k] - means[k - 1]).norm());
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    const double ratio = steps[steps.size() / 2] / spread;
    if (ratio < kRepeatedStepFraction) {
      AddFinding(
          &out, "positions_like_samples", Severity::kWarning,
          Format("the file was read as positions (no header, few rows), but its rows barely move "
                 "from one to the next (median step %.2g %% of their spread, where positions "
                 "turn to a new orientation at every row): it looks like a raw log, each sample "
                 "taken for a position",
                 100 * ratio),
          {{"median_step_fraction", ratio}, {"limit", kRepeatedStepFraction}});
    }
  }
}

// The fit: convergence, misfit, scatter, the prior, the degrees of freedom, the model asked for.
void FitFindings(const DiagnosisInput& input, const std::vector<Vec3>& means,
                 std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  const CalibrationResult& r = *input.result;
  const bool known = r.frame == Frame::kPlatform;
  if (!r.summary.converged()) {
    AddFinding(&out, "not_converged", Severity::kFailure,
               "the solver did not converge: " + r.summary.termination_message);
  }
  // The misfit fails the result unless the samples' own noise explains it (a scatter ratio
  // below kScatterWarning: then the readings are merely noisy, and the covariance says so).
  const double misfit = MisfitFraction(r, means);
  const bool noise_explains = std::isfinite(r.scatter_ratio) && r.scatter_ratio <= kScatterWarning;
  if (misfit > kMisfitFailure && !noise_explains) {
    AddFinding(
        &out, "misfit", Severity::kFailure,
        known ? Format("the residuals of the known orientations are %.2g %% of g RMS, beyond "
                       "%.0f %%: the orientation file does not describe these positions (lines "
                       "out of order or missing, or another frame or sign convention)",
                       100 * misfit, 100 * kMisfitFailure)
              : Format("the calibrated readings miss gravity by %.2g %% of g RMS, beyond %.0f "
                       "%%: the positions do not fit one sensor (two sensors interleaved, "
                       "positions taken while moving, or the wrong gravity or model)",
                       100 * misfit, 100 * kMisfitFailure),
        {{"rms_fraction_of_g", misfit}, {"limit", kMisfitFailure}});
  }
  if (std::isfinite(r.scatter_ratio) && r.scatter_ratio > kScatterNote) {
    const bool warn = r.scatter_ratio > kScatterWarning;
    AddFinding(
        &out, "scatter_ratio", warn ? Severity::kWarning : Severity::kNote,
        Format("the positions scatter %.3g times more than the noise of their samples explains%s; "
               "the uncertainties are inflated by that factor",
               r.scatter_ratio,
               warn ? ": something other than noise dominates (positions not still, drift, a "
                      "model that does not fit this sensor)"
                    : ""),
        {{"scatter_ratio", r.scatter_ratio}});
  }
  // A random-walk prior that the positions contradict: their whitened sum far below its
  // expectation m − P (χ² lower tail beyond 0.1 %) means q is far larger than this bias's walk,
  // and the posterior's uncertainties are widened by the prior, not by the data.
  if (r.drift && r.drift->random_walk && std::isfinite(r.scatter_ratio) && r.summary.converged()) {
    const double dof = static_cast<double>(r.positions_used() - NumParameters(r.model));
    if (dof > 0 && r.scatter_ratio * r.scatter_ratio * dof <
                       internal::ChiSquareQuantile(1.0 - kPriorContradictionProbability, dof)) {
      AddFinding(
          &out, "loose_random_walk", Severity::kWarning,
          Format("the positions scatter %.3g times what the bias's random walk q and the samples' "
                 "noise predict: q is larger than this bias wanders, and the uncertainties are "
                 "widened by the prior rather than the data; give the random walk measured for "
                 "this sensor, or a constant, linear or spline bias without one",
                 r.scatter_ratio),
          {{"scatter_ratio", r.scatter_ratio}});
    }
  }
  // No degrees of freedom: the fit passes through every position, and nothing checks it (a
  // posterior with a random-walk prior never passes through them all).
  if (r.degrees_of_freedom == 0 && r.summary.converged() && !(r.drift && r.drift->random_walk)) {
    const int parameters =
        NumParameters(r.model) + (r.drift ? 3 * static_cast<int>(r.drift->D.cols()) : 0);
    AddFinding(
        &out, "exactly_determined", Severity::kWarning,
        Format("%d positions fitted for %d parameters: the fit passes through every one of them, "
               "so no residual, uncertainty or held-out position checks it; add positions",
               r.positions_used(), parameters),
        {{"parameters", static_cast<double>(parameters)}});
  }
  // Round-off residuals with degrees of freedom left: not independent noisy readings. Only where
  // σ̂ was estimated: the baselines (modulus, ellipsoid) estimate none, and their σ̂ of 0 said
  // every real recording was fitted to round-off.
  if (r.degrees_of_freedom > 0 && r.summary.converged() && r.covariance.size() > 0) {
    double signal = 0;
    for (int a = 0; a < 3; ++a) signal = std::max(signal, std::abs(r.params.K(a, a)) * r.gravity);
    if (r.residual_sigma <= 1e-9 * signal) {
      AddFinding(
          &out, "exact_fit", Severity::kWarning,
          Format("the positions are fitted to round-off (residual sigma %.3g raw) with %d degrees "
                 "of freedom: they are not independent noisy readings (repeated rows, or "
                 "noise-free data), and the uncertainties mean nothing",
                 r.residual_sigma, r.degrees_of_freedom),
          {{"residual_sigma", r.residual_sigma}});
    }
  }
  if (input.selection && r.model == ModelKind::kQuadratic &&
      input.selection->chosen == ModelKind::kLinear) {
    AddFinding(&out, "model_choice", Severity::kWarning,
               "the quadratic model was asked for, but the data do not support it: " +
                   input.selection->reason);
  }
  if (!r.crossval_note.empty()) {
    AddFinding(&out, "crossval_unavailable", Severity::kNote,
               "held-out validation: " + r.crossval_note);
  }
}

// The screening's findings, and the held-out errors far beyond the typical one that it did not
// flag (screening off, or too few degrees of freedom to test).
void OutlierFindings(const DiagnosisInput& input, std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  const CalibrationResult& r = *input.result;
  const std::vector<Position>& positions = *input.positions;
  const char* unit = input.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g";
  std::vector<bool> found(positions.size(), false);
  int excluded = 0;
  for (const OutlierFinding& o : r.outliers) {
    found[static_cast<std::size_t>(o.position)] = true;
    excluded += o.excluded;
    AddFinding(
        &out, "outlier", Severity::kWarning,
        Format("position %d disagrees with the others (%s = %.1f, beyond %.2f): %s; it may have "
               "moved or been bumped during its interval",
               o.position + 1, std::string(ToString(o.statistic)).c_str(), o.t, o.threshold,
               o.excluded ? "left out of the fit" : "kept in the fit"),
        {{"position", o.position + 1}, {"statistic", o.t}, {"threshold", o.threshold}});
  }
  if (excluded > 0 && excluded >= input.max_excluded) {
    AddFinding(&out, "outlier_limit", Severity::kWarning,
               Format("%d positions were left out, the most allowed: more may disagree (raise the "
                      "limit to test further)",
                      excluded),
               {{"excluded", excluded}});
  }
  // Only where the screening did not test every position: where it did, its test (Student t,
  // Bonferroni) is the judgement, and this cruder rule would contradict it.
  const bool screened_all = r.screening != OutlierPolicy::kOff && r.outlier_note.empty();
  if (!screened_all && r.crossval_rms && r.crossval_errors.size() == positions.size() &&
      positions.size() >= 8) {
    std::vector<double> magnitudes;
    for (double e : r.crossval_errors) magnitudes.push_back(std::abs(e));
    const double typical = 1.4826 * Median(magnitudes);  // σ of a zero-mean normal from |e|
    for (std::size_t k = 0; k < magnitudes.size(); ++k) {
      if (typical > 0 && magnitudes[k] > 5.0 * typical && !found[k]) {
        AddFinding(
            &out, "held_out_outlier", Severity::kWarning,
            Format("position %zu: held-out |f| - g = %.3g %s, %.1f times the typical: it may "
                   "have moved or been bumped",
                   k + 1, r.crossval_errors[k], unit, magnitudes[k] / typical),
            {{"position", static_cast<double>(k + 1)}, {"ratio", magnitudes[k] / typical}});
      }
    }
  }
}

// Where the positions leave the sphere uncovered, what they barely determine, and gravity and
// units that do not look like Earth's.
void CoverageFindings(const DiagnosisInput& input, const std::vector<Vec3>& means,
                      std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  const CalibrationResult& r = *input.result;
  const bool known = r.frame == Frame::kPlatform;
  if (!known && !r.directions.empty()) {
    std::vector<Vec3> used;
    for (std::size_t k = 0; k < r.directions.size(); ++k) {
      if (!r.excluded(k)) used.push_back(r.directions[k]);
    }
    const auto [gap_deg, where] = LargestGap(used);
    if (gap_deg > 60.0) {
      AddFinding(&out, "coverage_gap", Severity::kWarning,
                 Format("no position within %.0f deg of the direction (%.2f, %.2f, %.2f): the "
                        "calibration is extrapolated there; add positions facing it",
                        gap_deg, where(0), where(1), where(2)),
                 {{"gap_deg", gap_deg}});
    }
  }
  PoorlyDetermined(r, &out);
  // Gravity and units: a gravity no place on Earth has, or uncalibrated magnitudes that look like
  // the other unit than gravity's.
  const double g_ms2 =
      input.unit == ForceUnit::kMetersPerSecond2 ? r.gravity : r.gravity * kStandardGravity_ms2;
  if (std::abs(g_ms2 / kStandardGravity_ms2 - 1.0) > 0.01) {
    AddFinding(
        &out, "gravity_value", Severity::kWarning,
        Format("gravity is %.6g m/s2, while on Earth it lies within 9.76-9.84 m/s2 (surface, any "
               "latitude): the scale factors carry that error",
               g_ms2),
        {{"gravity_ms2", g_ms2}});
  } else if (!means.empty()) {
    std::vector<double> norms;
    for (const Vec3& p : means) norms.push_back(p.norm());
    const double median = Median(norms);
    const bool in_g = input.unit == ForceUnit::kStandardGravity;
    if (!in_g && std::abs(median - 1.0) < 0.2) {
      AddFinding(
          &out, "units", Severity::kWarning,
          Format("the readings' median magnitude is %.4g, about 1 g, while gravity is %.6g m/s2: "
                 "if they are in g, calibrate in g (the result then maps g to g)",
                 median, r.gravity),
          {{"median_norm", median}, {"gravity", r.gravity}});
    } else if (in_g && std::abs(median / kStandardGravity_ms2 - 1.0) < 0.2) {
      AddFinding(
          &out, "units", Severity::kWarning,
          Format("the readings' median magnitude is %.4g, about 9.8 m/s2, while the result is in "
                 "g: if they are in m/s2, calibrate in m/s2",
                 median),
          {{"median_norm", median}, {"gravity", r.gravity}});
    }
  }
}

// The gyroscope's findings, and each log's (prefixed with its name when there are several).
void SensorAndLogFindings(const DiagnosisInput& input, std::vector<Finding>* out_findings) {
  std::vector<Finding>& out = *out_findings;
  const CalibrationResult& r = *input.result;
  if (input.gyroscope != nullptr) {
    for (Finding& f : GyroFindings(*input.gyroscope)) out.push_back(std::move(f));
  }
  for (const DiagnosedLog& l : input.logs) {
    for (Finding& f : LogFindings(l.log, l.detection)) {
      if (input.logs.size() > 1) f.message = l.name + ": " + f.message;
      const std::string constant_bias =
          ", which a constant bias does not explain (the held-out error shows its cost)";
      const std::size_t at = f.message.find(constant_bias);
      if (f.code == "drifting_rest" && r.drift && at != std::string::npos) {
        // The fit's bias follows time: the drift is modelled, not a defect of the result.
        f.severity = Severity::kNote;
        f.message.replace(at, constant_bias.size(),
                          ", which the fit's " + ToString(r.drift->basis.model) + " bias follows");
      }
      out.push_back(std::move(f));
    }
  }
}

}  // namespace

Diagnosis Diagnose(const DiagnosisInput& input) {
  Diagnosis d;
  std::vector<Finding>& out = d.findings;
  const std::vector<Vec3> means = Means(*input.positions);
  InputShapeFindings(input, means, &out);
  FitFindings(input, means, &out);
  OutlierFindings(input, &out);
  CoverageFindings(input, means, &out);
  SensorAndLogFindings(input, &out);
  // Failures first, then warnings, then notes; each kind in the order found.
  std::stable_sort(out.begin(), out.end(), [](const Finding& a, const Finding& b) {
    return static_cast<int>(a.severity) > static_cast<int>(b.severity);
  });
  return d;
}

}  // namespace accelcal
