#include "statistics/fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "core/text_format.hpp"
#include "solvers/drift_fit.hpp"
#include "solvers/solve.hpp"

namespace accelcal::internal {

namespace {

// The sandwich covariance with per-position noise, inflated by the scatter ratio (calibrate.hpp):
// the rows u_k of S = Σ u_k u_kᵀ, the unit normals n_k, the residuals r_k and S⁻¹.
template <typename RowsU, typename InverseS>
Eigen::MatrixXd SampleNoiseCovariance(const RowsU& U, const std::vector<Vec3>& normals,
                                      const std::vector<Vec3>& residuals, const InverseS& S_inverse,
                                      const std::vector<Vec3>& sigmas, CalibrationResult* result) {
  const auto m = static_cast<Eigen::Index>(normals.size());
  Eigen::VectorXd variance(m);
  double chi2 = 0;
  for (Eigen::Index k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const Vec3& n = normals[i];
    variance(k) = n.cwiseAbs2().dot(sigmas[i].cwiseAbs2());
    chi2 += std::pow(n.dot(residuals[i]), 2) / variance(k);
  }
  const Eigen::MatrixXd meat = U.transpose() * variance.asDiagonal() * U;
  const double ratio2 = chi2 / result->degrees_of_freedom;
  result->noise_source = "samples";
  result->scatter_ratio = std::sqrt(ratio2);
  return std::max(1.0, ratio2) * S_inverse * meat * S_inverse;
}

// The bias drift's fit from the constant-bias solution `out` (drift_fit.hpp) and its statistics:
// fills `fit` (parameters, residuals, covariance, screening) and returns its summary.
Summary FitDrift(const Problem& problem, const CalibrationOptions& options, const SolverOutput& out,
                 Fit* fit) {
  const BiasTimeBasis basis =
      options.bias_basis ? *options.bias_basis
                         : BiasTimeBasis::For(options.bias_model, options.position_times_s);
  const bool prior = options.bias_random_walk && basis.model.kind == BiasModelKind::kSpline;
  std::optional<RandomWalkPrior> random_walk;
  if (prior) random_walk = RandomWalkPrior{*options.bias_random_walk, options.reading_sigmas};
  const DriftFit drift = SolveDrift(problem, basis, options.position_times_s, out.params, out.dirs,
                                    options.joint, random_walk);
  if (drift.summary.rank_deficient) {
    throw DataError(internal::Format(
        "the positions' times do not determine a %s bias (reciprocal condition %.2g): %s",
        ToString(options.bias_model).c_str(), std::max(0.0, drift.summary.reciprocal_condition),
        prior ? "its random walk q is so large that the knots are left to the positions alone; "
                "give a smaller q, or fewer knots"
              : "spread the orientations over the session, each visited early and late"));
  }
  CalibrationResult& result = fit->result;
  const int P = NumParameters(options.model), J = basis.size();
  const int n = P + 3 * J;
  result.params = drift.params;
  result.directions = drift.dirs;
  result.residuals = drift.residuals;
  const int m = problem.positions();
  BiasDrift& d = result.drift.emplace();
  d.basis = basis;
  d.D = drift.D;
  d.times_s = options.position_times_s;
  if (prior) d.random_walk = options.bias_random_walk;

  Summary summary = out.summary;
  summary.iterations += drift.summary.iterations;
  summary.termination = drift.summary.termination;
  summary.termination_message =
      ToString(options.bias_model) + " bias: " + drift.summary.termination_message;
  // J of the drift's own problem (with a prior, whitened) from its start to its solution.
  summary.initial_cost = drift.summary.initial_cost;
  summary.final_cost = drift.summary.final_cost;
  const bool invertible = drift.S_inverse.rows() == n;
  // The parameters the readings pay for: P + 3J, or with the prior Σ h_k (the prior pays for the
  // rest), rounded up.
  std::vector<double> leverages(static_cast<std::size_t>(m), 0.0);
  double used = n;
  if (invertible) {
    used = 0;
    for (std::size_t k = 0; k < leverages.size(); ++k) {
      const Eigen::VectorXd u = drift.U.row(static_cast<Eigen::Index>(k)).transpose();
      leverages[k] = u.dot(drift.S_inverse * u);
      used += leverages[k];
    }
  }
  const int spent = prior ? static_cast<int>(std::ceil(used - 1e-9)) : n;
  result.degrees_of_freedom = m - spent;
  if (prior && options.outliers.policy != OutlierPolicy::kOff) {
    // The test's studentized residuals are least-squares ones; a posterior's are shrunk by the
    // prior, and their t would be meaningless (a leverage sum near m made it ±inf).
    fit->screening.note =
        "outlier screening does not run with a random-walk prior (its residuals are shrunk by "
        "the prior, not least-squares ones): the held-out errors show a discordant position";
  } else if (options.outliers.policy != OutlierPolicy::kOff && summary.converged() && invertible) {
    fit->screening =
        ScreenWithLeverages(drift.normals, leverages, spent,
                            "the " + std::string(ToString(options.model)) + " model with a " +
                                ToString(options.bias_model) + " bias",
                            drift.residuals, SignalAmplitude(drift.params, options.gravity),
                            options.outliers.false_alarm_probability);
  }
  if (prior && invertible && m > P) {
    // The whitened sum with the prior's part has E J = m − P at the optimum (its residual count
    // less its parameters): the posterior covariance S⁻¹, widened by the scatter ratio when the
    // noise and the random walk do not explain the positions.
    const double ratio2 = summary.final_cost / (m - P);
    // σ̂ [raw] as without the prior (the unweighted sum of squares over the degrees of freedom
    // the readings keep): a figure of the scatter, not the covariance's.
    double sum2 = 0;
    for (const Vec3& r : drift.residuals) sum2 += r.squaredNorm();
    if (result.degrees_of_freedom > 0) {
      result.residual_sigma = std::sqrt(sum2 / result.degrees_of_freedom);
    }
    result.noise_source = "samples";
    result.scatter_ratio = std::sqrt(ratio2);
    d.covariance = std::max(1.0, ratio2) * drift.S_inverse;
    result.covariance = d.covariance.topLeftCorner(P, P);
  } else if (result.degrees_of_freedom > 0 && invertible) {
    const double sigma2 = summary.final_cost / result.degrees_of_freedom;
    result.residual_sigma = std::sqrt(sigma2);
    d.covariance = sigma2 * drift.S_inverse;
    if (!options.reading_sigmas.empty()) {
      d.covariance = SampleNoiseCovariance(drift.U, drift.normals, result.residuals,
                                           drift.S_inverse, options.reading_sigmas, &result);
    }
    result.covariance = d.covariance.topLeftCorner(P, P);
  }
  return summary;
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
  const bool drifting = !options.bias_model.constant() && out.summary.converged();
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
  if (drifting) {
    result.summary = FitDrift(problem, options, out, &fit);
    result.summary.time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return fit;
  }
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
      std::vector<Vec3> residuals;
      residuals.reserve(problem.readings.size());
      for (std::size_t k = 0; k < problem.readings.size(); ++k) {
        residuals.push_back(problem.readings[k] -
                            PredictRaw(out.params, Vec3(options.gravity * out.dirs[k])));
      }
      covariance = SampleNoiseCovariance(rows.U, rows.normals, residuals, inverse,
                                         options.reading_sigmas, &result);
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
  if (!options.bias_model.constant() && options.position_times_s.size() != readings.size()) {
    throw std::invalid_argument("a " + ToString(options.bias_model) + " bias needs one time per " +
                                "reading: position_times_s has " +
                                std::to_string(options.position_times_s.size()) + " for " +
                                std::to_string(readings.size()) + " readings");
  }
  if (options.frame == Frame::kXFirst) return CalibrateXFirst(readings, options, Frame::kXFirst);
  std::vector<Vec3> mirrored;
  mirrored.reserve(readings.size());
  for (const Vec3& p : readings) mirrored.push_back(MirrorAxes(p));
  CalibrationOptions mirrored_options = options;
  if (options.initial_params) mirrored_options.initial_params = MirrorAxes(*options.initial_params);
  for (Vec3& s : mirrored_options.reading_sigmas) s = MirrorAxes(s).cwiseAbs();
  if (options.bias_random_walk) {
    mirrored_options.bias_random_walk = MirrorAxes(*options.bias_random_walk).cwiseAbs();
  }
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
  if (result.drift) result.drift = MirrorAxes(*result.drift, options.model);
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

CalibrationOptions OptionsForPositions(const CalibrationOptions& options,
                                       const std::vector<int>& keep) {
  CalibrationOptions subset = options;
  if (!options.reading_sigmas.empty()) {
    subset.reading_sigmas.clear();
    for (int k : keep) subset.reading_sigmas.push_back(options.reading_sigmas[std::size_t(k)]);
  }
  if (!options.bias_model.constant()) {
    if (!options.bias_basis) {
      subset.bias_basis = BiasTimeBasis::For(options.bias_model, options.position_times_s);
    }
    subset.position_times_s.clear();
    for (int k : keep) subset.position_times_s.push_back(options.position_times_s[std::size_t(k)]);
  }
  return subset;
}

void SpreadOverAllPositions(const std::vector<Vec3>& readings, const std::vector<int>& keep,
                            const std::vector<double>& times_s, CalibrationResult* fit) {
  if (fit->drift) fit->drift->times_s = times_s;
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
    const Vec3 reading = readings[k] - (fit->drift ? fit->drift->Offset(times_s[k]) : Vec3::Zero());
    const std::optional<Vec3> f = SpecificForce(fit->params, reading);
    directions[k] = f && f->norm() > 0 ? Vec3(f->normalized()) : Vec3::UnitZ();
    residuals[k] = reading - PredictRaw(fit->params, Vec3(fit->gravity * directions[k]));
  }
  fit->directions = std::move(directions);
  fit->residuals = std::move(residuals);
}

}  // namespace accelcal::internal
