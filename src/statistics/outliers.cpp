#include "statistics/outliers.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "accelcal/error.hpp"
#include "statistics/fit.hpp"
#include "statistics/screening.hpp"
#include "statistics/student_t.hpp"

namespace accelcal::internal {

OutlierFinding Screening::Finding(int index) const {
  OutlierFinding finding;
  finding.position = index;
  finding.t = t[std::size_t(index)];
  finding.threshold = StudentTTwoSidedQuantile(per_position_probability, degrees_of_freedom);
  finding.degrees_of_freedom = degrees_of_freedom;
  finding.normal_residual = e[std::size_t(index)];
  finding.scatter = scatter;
  return finding;
}

namespace {

// The leverages h_k = u_kᵀ S⁻¹ u_k on the model's P free parameters only (S⁻¹ is the identity on
// the fixed ones, where u_k has no business); lazyProduct keeps the fixed-size product off Eigen's
// GEMV path (measured: half the instructions; one GEMM over all rows, a triangular factor, or the
// symmetric half as scalar loops cost more).
template <int P>
std::vector<double> Leverages(const InformationRows& rows, const Mat12& S_inverse,
                              const std::vector<int>& cols) {
  Eigen::Matrix<double, P, P> M;
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) M(i, j) = S_inverse(cols[i], cols[j]);
  }
  const auto m = static_cast<std::size_t>(rows.U.rows());
  std::vector<double> h(m);
  Eigen::Matrix<double, P, 1> u;
  for (std::size_t k = 0; k < m; ++k) {
    for (int i = 0; i < P; ++i) u(i) = rows.U(static_cast<Eigen::Index>(k), cols[i]);
    h[k] = u.dot(M.lazyProduct(u));
  }
  return h;
}

}  // namespace

Screening ScreenPositions(const InformationRows& rows, const Mat12& S_inverse, ModelKind model,
                          const std::vector<Vec3>& residuals, double signal,
                          double false_alarm_probability) {
  const int m = static_cast<int>(residuals.size());
  const int P = NumParameters(model);
  const std::string what = "the " + std::string(ToString(model)) + " model";
  if (m - P < 2) {
    return ScreenWithLeverages(rows.normals, {}, P, what, residuals, signal,
                               false_alarm_probability);
  }
  const std::vector<int>& cols = ActiveColumns(model);
  return ScreenWithLeverages(
      rows.normals,
      cols.size() == 9 ? Leverages<9>(rows, S_inverse, cols) : Leverages<12>(rows, S_inverse, cols),
      P, what, residuals, signal, false_alarm_probability);
}

Screening ScreenWithLeverages(const std::vector<Vec3>& normals,
                              const std::vector<double>& leverages, int P, const std::string& what,
                              const std::vector<Vec3>& residuals, double signal,
                              double false_alarm_probability) {
  Screening out;
  const int m = static_cast<int>(residuals.size());
  const int nu = m - P;
  if (nu < 2) {
    out.note = "outlier screening needs at least " + std::to_string(P + 2) + " positions for " +
               what + ", got " + std::to_string(m);
    return out;
  }
  out.e.resize(static_cast<std::size_t>(m));
  double sum2 = 0;
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    out.e[i] = residuals[i].dot(normals[i]);
    sum2 += out.e[i] * out.e[i];
  }
  const double s2 = sum2 / nu;
  out.ran = true;
  out.scatter = std::sqrt(s2);
  out.degrees_of_freedom = nu - 1;
  out.per_position_probability = false_alarm_probability / m;  // Bonferroni
  out.t.assign(static_cast<std::size_t>(m), std::nan(""));
  // Positions fitted to round-off (simulated exact data) have no scatter to test against.
  const double round_off = 64 * std::numeric_limits<double>::epsilon() * signal;
  if (!(s2 > round_off * round_off)) return out;

  std::vector<int> untested;
  std::vector<double> scaled;  // |e_k| / √(1 − h_k), for the robust scale
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double h = leverages[i];
    if (!(1.0 - h > kMinUntestedMargin)) {
      untested.push_back(k + 1);
      scaled.push_back(0.0);
      continue;
    }
    scaled.push_back(std::abs(out.e[i]) / std::sqrt(1.0 - h));
    const double r2 = out.e[i] * out.e[i] / (s2 * (1.0 - h));
    const double t = r2 >= nu ? INFINITY : std::sqrt(r2 * (nu - 1) / (nu - r2));
    out.t[i] = std::copysign(t, out.e[i]);
    if (out.most_discordant < 0 || t > std::abs(out.t[std::size_t(out.most_discordant)])) {
      out.most_discordant = k;
    }
  }
  if (out.most_discordant >= 0) {
    const double t_max = std::abs(out.t[std::size_t(out.most_discordant)]);
    out.significant = StudentTTwoSidedP(t_max, nu - 1) < out.per_position_probability;
    std::vector<double> sorted = scaled;
    std::nth_element(sorted.begin(), sorted.begin() + m / 2, sorted.end());
    const double robust_scale = 1.4826 * sorted[std::size_t(m / 2)];
    const double v_max = *std::max_element(scaled.begin(), scaled.end()) / robust_scale;
    out.suspicious = !(StudentTTwoSidedP(v_max, nu - 1) >= out.per_position_probability);
  }
  if (!untested.empty()) {
    out.note = "position";
    out.note += untested.size() > 1 ? "s " : " ";
    for (std::size_t i = 0; i < untested.size(); ++i) {
      out.note += (i ? ", " : "") + std::to_string(untested[i]);
    }
    out.note += " not screened: the other positions do not determine the fit without them";
  }
  return out;
}

namespace {

// The readings (and their sigmas) of the positions in `keep`.
CalibrationOptions SubsetOptions(const CalibrationOptions& options, const std::vector<int>& keep,
                                 const ModelParameters& start) {
  CalibrationOptions subset = OptionsForPositions(options, keep);
  subset.cross_validate = false;
  if (options.method != SolverMethod::kEllipsoid) {
    subset.initialization = Initialization::kGiven;
    subset.initial_params = start;
  }
  return subset;
}

}  // namespace

// The fit with the screening of OutlierOptions: the generalised ESD of statistics/screening.hpp,
// each step's test the Student t of ScreenPositions on the refit without the positions removed so
// far. The refits run only when the first step is significant or the robust scale finds a position
// suspicious (Screening); a discordant position whose removal leaves positions that cannot be
// fitted is reported as such, not removed.

CalibrationResult CalibrateScreened(const std::vector<Vec3>& readings,
                                    const CalibrationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Fit first = CalibrateInFrame(readings, options);
  CalibrationResult& full = first.result;
  if (options.outliers.policy == OutlierPolicy::kOff || !full.summary.converged()) return full;
  internal::Screening screening = std::move(first.screening);
  std::string note = screening.note;
  if (!screening.significant && !screening.suspicious) {
    full.outlier_note = std::move(note);
    return full;
  }
  // Each step's refit without the positions removed so far, and those positions' complement.
  std::vector<CalibrationResult> fits;
  std::vector<std::vector<int>> keeps;
  std::vector<int> keep(readings.size());
  for (std::size_t k = 0; k < keep.size(); ++k) keep[k] = static_cast<int>(k);
  std::optional<OutlierFinding> unremovable;  // discordant, but the rest cannot be fitted
  bool screened = true;                       // the last refit could be screened
  const EsdOutcome outcome =
      GeneralisedEsd(options.outliers, [&](std::size_t) -> std::optional<EsdStep> {
        if (!screened || screening.most_discordant < 0) return std::nullopt;
        OutlierFinding finding = screening.Finding(screening.most_discordant);
        finding.position = keep[std::size_t(finding.position)];
        std::vector<int> rest;
        std::vector<Vec3> rest_readings;
        for (int k : keep) {
          if (k == finding.position) continue;
          rest.push_back(k);
          rest_readings.push_back(readings[std::size_t(k)]);
        }
        const ModelParameters& start = fits.empty() ? full.params : fits.back().params;
        std::optional<Fit> refit;
        std::string why;
        try {
          refit = CalibrateInFrame(rest_readings, SubsetOptions(options, rest, start));
          if (!refit->result.summary.converged()) why = "the fit without it did not converge";
        } catch (const DataError& e) {
          why = e.what();
        }
        if (!why.empty()) {
          if (std::abs(finding.t) > finding.threshold) {
            unremovable = finding;
            note = "position " + std::to_string(finding.position + 1) +
                   " disagrees but cannot be left out: without it, " + why;
          }
          return std::nullopt;
        }
        fits.push_back(std::move(refit->result));
        keeps.push_back(rest);
        keep = std::move(rest);
        screening = std::move(refit->screening);
        screened = screening.ran;
        return EsdStep{finding, std::abs(finding.t) > finding.threshold};
      });
  const std::size_t steps = outcome.steps.size(), discordant = outcome.discordant;
  const int max_steps = std::max(1, options.outliers.max_excluded);
  if (!unremovable && discordant == steps && static_cast<int>(steps) == max_steps &&
      screening.significant) {
    note = "more positions may disagree: the screening tests at most " + std::to_string(max_steps);
  }
  const std::size_t excluded = outcome.excluded;
  CalibrationResult result = excluded > 0 ? std::move(fits[excluded - 1]) : std::move(full);
  if (excluded > 0) {
    internal::SpreadOverAllPositions(readings, keeps[excluded - 1], options.position_times_s,
                                     &result);
    // The summary tells the whole solve: where it started, every fit's iterations and time.
    Summary& summary = result.summary;
    summary.initialization = full.summary.initialization;
    summary.initialization_note = full.summary.initialization_note;
    summary.initial_cost = full.summary.initial_cost;
    for (std::size_t i = 0; i + 1 < excluded; ++i) summary.iterations += fits[i].summary.iterations;
    summary.iterations += full.summary.iterations;
  }
  result.outliers = DiscordantFindings(outcome);
  if (unremovable && discordant == steps) result.outliers.push_back(*unremovable);
  result.outlier_note = std::move(note);
  result.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace accelcal::internal
