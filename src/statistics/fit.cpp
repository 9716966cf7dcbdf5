#include "statistics/fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "core/text_format.hpp"
#include "solvers/solve.hpp"

namespace accelcal::internal {

namespace {

// The sandwich covariance with per-position noise, inflated by the scatter ratio (calibrate.hpp).
internal::Mat12 SampleNoiseCovariance(const Problem& problem, const internal::SolverOutput& out,
                                      const internal::InformationRows& rows,
                                      const internal::Mat12& S_inverse,
                                      const std::vector<Vec3>& sigmas, CalibrationResult* result) {
  const int m = problem.positions();
  Eigen::VectorXd variance(m);
  double chi2 = 0;
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const Vec3& n = rows.normals[i];
    variance(k) = n.cwiseAbs2().dot(sigmas[i].cwiseAbs2());
    const Vec3 residual =
        problem.readings[i] - PredictRaw(out.params, Vec3(problem.gravity * out.dirs[i]));
    chi2 += std::pow(n.dot(residual), 2) / variance(k);
  }
  const internal::Mat12 meat = rows.U.transpose() * variance.asDiagonal() * rows.U;
  const double ratio2 = chi2 / result->degrees_of_freedom;
  result->noise_source = "samples";
  result->scatter_ratio = std::sqrt(ratio2);
  return std::max(1.0, ratio2) * S_inverse * meat * S_inverse;
}

// The fit in the x-first gauge; `frame` only names parameters in messages (the z-first fit runs
// here on mirrored readings).
Fit CalibrateXFirst(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                    Frame frame) {
  const auto t0 = std::chrono::steady_clock::now();
  CheckData(readings, options.model);
  const Problem data{readings, options.gravity, options.model};

  Start start = Initialise(data, options.initialization, options.initial_params);
  internal::SolverOutput out;
  if (options.method == SolverMethod::kEllipsoid) {
    if (start.used != Initialization::kEllipsoidFit) {
      throw DataError("the ellipsoid method cannot run: " + start.note);
    }
    out.params = start.params;
    out.dirs = std::move(start.dirs);
    out.summary.method = SolverMethod::kEllipsoid;
    out.summary.termination = TerminationType::kClosedForm;
    out.summary.termination_message =
        start.fit_kind == EllipsoidFitKind::kAlgebraic
            ? "algebraic fit (paper 001 eq. (16)-(18))"
            : "ellipsoid-specific fit (Li & Griffiths 2004): the algebraic quadric of paper "
              "001 eq. (16)-(18) is no ellipsoid";
    out.summary.initial_cost = out.summary.final_cost = internal::Cost(data, out.params, out.dirs);
  } else {
    out = SolveFrom(data, start.params, std::move(start.dirs), options);
    MultiStart(data, options, &out);
  }
  // The readings the final fit was solved for (shifted by the bias correction).
  std::vector<Vec3> fit_readings;
  if (options.estimator == Estimator::kBiasCorrected && out.summary.converged()) {
    fit_readings = CorrectBias(readings, options, &out);
  }
  const Problem problem{fit_readings.empty() ? readings : fit_readings, options.gravity,
                        options.model};
  out.summary.initialization = start.used;
  out.summary.initialization_note = start.note;

  // Observability at the solution: a (near) singular reduced information matrix means some
  // parameter is not determined by these positions, whatever the solver returned.
  internal::InformationRows rows;
  const internal::Information info =
      internal::ComputeInformation(problem, out.params, out.dirs, &rows);
  ThrowIfUnobservable(info, options.model, frame);
  // A solver that did not converge on poorly conditioned data is usually wandering along a
  // valley of nearly equal fits: say which parameter the positions barely determine.
  if (!out.summary.converged() && info.rcond < internal::kPoorInformationRcond) {
    char buf[200];
    internal::FormatTo(
        buf, sizeof buf,
        "; the positions barely determine parameter %s (reciprocal condition %.2g): add "
        "positions with other orientations",
        SlotName(info.weakest, frame).c_str(), info.rcond);
    out.summary.termination_message += buf;
  }

  Fit fit;
  CalibrationResult& result = fit.result;
  result.model = options.model;
  result.gravity = options.gravity;
  result.params = out.params;
  result.directions = out.dirs;
  result.residuals.reserve(readings.size());
  for (std::size_t k = 0; k < readings.size(); ++k) {
    result.residuals.push_back(readings[k] -
                               PredictRaw(out.params, Vec3(options.gravity * out.dirs[k])));
  }
  const int P = NumParameters(options.model);
  result.degrees_of_freedom = static_cast<int>(readings.size()) - P;
  const bool screen = options.outliers.policy != OutlierPolicy::kOff && out.summary.converged();
  const bool covariance_wanted =
      result.degrees_of_freedom > 0 && IsMaximumLikelihood(options.method);
  const internal::Mat12 inverse =
      screen || covariance_wanted ? info.Inverse() : internal::Mat12::Zero();
  if (screen) {
    fit.screening =
        internal::ScreenPositions(rows, inverse, options.model, result.residuals,
                                  internal::SignalAmplitude(out.params, options.gravity),
                                  options.outliers.false_alarm_probability);
  }
  if (covariance_wanted) {
    const double sigma2 = out.summary.final_cost / result.degrees_of_freedom;
    result.residual_sigma = std::sqrt(sigma2);
    internal::Mat12 covariance = sigma2 * inverse;
    if (!options.reading_sigmas.empty()) {
      covariance =
          SampleNoiseCovariance(problem, out, rows, inverse, options.reading_sigmas, &result);
    }
    const std::vector<int>& cols = ActiveColumns(options.model);
    result.covariance.resize(P, P);
    for (int i = 0; i < P; ++i) {
      for (int j = 0; j < P; ++j) result.covariance(i, j) = covariance(cols[i], cols[j]);
    }
  }
  result.summary = out.summary;
  result.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return fit;
}

}  // namespace

// The fit in the requested frame (frame.hpp): z-first is the x-first fit of the mirrored readings
// (the outlier statistics do not depend on the gauge).
Fit CalibrateInFrame(const std::vector<Vec3>& readings, const CalibrationOptions& options) {
  if (options.frame == Frame::kXFirst) return CalibrateXFirst(readings, options, Frame::kXFirst);
  std::vector<Vec3> mirrored;
  mirrored.reserve(readings.size());
  for (const Vec3& p : readings) mirrored.push_back(MirrorAxes(p));
  CalibrationOptions mirrored_options = options;
  if (options.initial_params) mirrored_options.initial_params = MirrorAxes(*options.initial_params);
  for (Vec3& s : mirrored_options.reading_sigmas) s = MirrorAxes(s).cwiseAbs();
  Fit fit = CalibrateXFirst(mirrored, mirrored_options, Frame::kZFirst);
  CalibrationResult& result = fit.result;
  result.frame = Frame::kZFirst;
  result.params = MirrorAxes(result.params);
  for (Vec3& c : result.directions) c = MirrorAxes(c);
  for (Vec3& r : result.residuals) r = MirrorAxes(r);
  if (result.covariance.size() > 0) {
    const Eigen::VectorXd d = MirrorSigns(options.model);
    result.covariance = d.asDiagonal() * result.covariance * d.asDiagonal();
  }
  return fit;
}

void CheckDistinctReadings(const std::vector<Vec3>& readings) {
  // Sorted by reading, equal readings by index: each group's first entry is the original, the
  // others repeat it. The repeat earliest in the input is named.
  std::vector<std::size_t> order(readings.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Vec3& p = readings[a];
    const Vec3& q = readings[b];
    if (p != q) return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
    return a < b;
  });
  std::size_t repeat = readings.size(), original = 0, group_first = 0;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || readings[order[i]] != readings[order[i - 1]]) {
      group_first = order[i];
    } else if (order[i] < repeat) {
      repeat = order[i];
      original = group_first;
    }
  }
  if (repeat < readings.size()) {
    throw DataError("position " + std::to_string(repeat + 1) + " repeats position " +
                    std::to_string(original + 1) +
                    " exactly: repeated rows are not independent positions (they would shrink "
                    "every uncertainty); remove them");
  }
}

void CheckReadingSigmas(const std::vector<Vec3>& sigmas, std::size_t readings) {
  if (sigmas.empty()) return;
  if (sigmas.size() != readings) {
    throw std::invalid_argument("reading_sigmas has " + std::to_string(sigmas.size()) +
                                " entries for " + std::to_string(readings) + " readings");
  }
  for (const Vec3& s : sigmas) {
    if (!s.allFinite() || !(s.minCoeff() > 0)) {
      throw std::invalid_argument("reading_sigmas must be finite and positive");
    }
  }
}

void SpreadOverAllPositions(const std::vector<Vec3>& readings, const std::vector<int>& keep,
                            CalibrationResult* fit) {
  std::vector<Vec3> directions(readings.size()), residuals(readings.size());
  std::vector<bool> kept(readings.size(), false);
  for (std::size_t i = 0; i < keep.size(); ++i) {
    const auto k = static_cast<std::size_t>(keep[i]);
    directions[k] = fit->directions[i];
    residuals[k] = fit->residuals[i];
    kept[k] = true;
  }
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (kept[k]) continue;
    const std::optional<Vec3> f = SpecificForce(fit->params, readings[k]);
    directions[k] = f && f->norm() > 0 ? Vec3(f->normalized()) : Vec3::UnitZ();
    residuals[k] = readings[k] - PredictRaw(fit->params, Vec3(fit->gravity * directions[k]));
  }
  fit->directions = std::move(directions);
  fit->residuals = std::move(residuals);
}

}  // namespace accelcal::internal
