#include "accelcal/model_selection.hpp"

#include <cmath>
#include <tuple>

#include <Eigen/Cholesky>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "core/text_format.hpp"
#include "statistics/fit.hpp"
#include "statistics/held_out.hpp"
#include "statistics/outliers.hpp"
#include "statistics/student_t.hpp"

namespace accelcal {

using internal::Format;

namespace {

Vec3 SquaredCoefficientT(const CalibrationResult& quadratic) {
  Vec3 t = Vec3::Constant(std::nan(""));
  if (quadratic.covariance.size() == 0) return t;
  const auto& slots = ParameterSlots(ModelKind::kQuadratic, quadratic.frame);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (slots[i].group != ParameterGroup::kK2) continue;
    const auto index = static_cast<Eigen::Index>(i);
    const double sd = std::sqrt(quadratic.covariance(index, index));
    if (sd > 0) t(slots[i].row) = quadratic.params.k2(slots[i].row) / sd;
  }
  return t;
}

// The largest |t_i| among those that are numbers (NaN when none is).
double LargestAbsolute(const Vec3& t) {
  double largest = std::nan("");
  for (int i = 0; i < 3; ++i) {
    if (!std::isnan(t(i)) && !(std::abs(t(i)) <= largest)) largest = std::abs(t(i));
  }
  return largest;
}

// The 0-based positions of `result`'s fit (the ones its screening did not exclude).
std::vector<int> PositionsInFit(const CalibrationResult& result, std::size_t readings) {
  std::vector<int> keep;
  for (std::size_t k = 0; k < readings; ++k) {
    if (!result.excluded(k)) keep.push_back(static_cast<int>(k));
  }
  return keep;
}

// The fit of `options.model` to the positions in `keep` (no screening of its own), spread back
// over all readings as Calibrate spreads a screened fit, with the findings and note of the
// screening that chose `keep` (`screened`), and validated with those positions held out.
CalibrationResult FitOnPositions(const std::vector<Vec3>& readings,
                                 const CalibrationOptions& options, const std::vector<int>& keep,
                                 const CalibrationResult& screened) {
  CalibrationOptions subset = internal::OptionsForPositions(options, keep);
  subset.cross_validate = false;
  subset.outliers.policy = OutlierPolicy::kOff;
  std::vector<Vec3> kept;
  kept.reserve(keep.size());
  for (int k : keep) kept.push_back(readings[std::size_t(k)]);
  CalibrationResult result = Calibrate(kept, subset);
  if (keep.size() < readings.size()) {
    internal::SpreadOverAllPositions(readings, keep, options.position_times_s, &result);
  }
  result.outliers = screened.outliers;
  result.outlier_note = screened.outlier_note;
  result.screening = screened.screening;
  if (result.summary.converged()) CrossValidate(readings, options, &result);
  return result;
}

}  // namespace

ModelChoice CalibrateChoosingModel(const std::vector<Vec3>& readings,
                                   const CalibrationOptions& options, bool auto_model) {
  ModelChoice choice;
  if (auto_model || (options.model == ModelKind::kQuadratic && options.cross_validate)) {
    choice.selection = SelectModel(readings, options);
  }
  if (auto_model) {
    choice.result = choice.selection->chosen_result();
  } else if (choice.selection && choice.selection->quadratic) {
    choice.result = *choice.selection->quadratic;
  } else {
    choice.result = Calibrate(readings, options);  // also the error of a quadratic fit that failed
  }
  return choice;
}

ModelSelection SelectModel(const std::vector<Vec3>& readings, CalibrationOptions options) {
  ModelSelection selection;
  options.cross_validate = true;
  CalibrationOptions linear_options = options;
  linear_options.model = ModelKind::kLinear;
  CalibrationOptions quadratic_options = options;
  quadratic_options.model = ModelKind::kQuadratic;
  if (quadratic_options.initial_params) quadratic_options.initial_params->k2.setZero();

  // The linear model alone, screened by itself, as Calibrate fits it: when there is nothing to
  // compare it with.
  const auto linear_alone = [&](const std::string& why_not_quadratic) {
    selection.linear = Calibrate(readings, linear_options);
    selection.screened_with = ModelKind::kLinear;
    selection.positions_used = PositionsInFit(selection.linear, readings.size());
    selection.reason = selection.linear.summary.converged() ? why_not_quadratic
                                                            : "the linear fit did not converge";
    return selection;
  };

  // The quadratic fit, with its screening and then (converged) its validation.
  try {
    selection.quadratic = Calibrate(readings, quadratic_options);
  } catch (const DataError& e) {
    selection.quadratic_error = e.what();
  }
  if (selection.quadratic && !selection.quadratic->summary.converged()) {
    selection.quadratic_error =
        "did not converge: " + selection.quadratic->summary.termination_message;
    selection.quadratic.reset();
  }
  if (!selection.quadratic) {
    return linear_alone("the quadratic model cannot be fitted (" + selection.quadratic_error + ")");
  }
  const CalibrationResult& quadratic = *selection.quadratic;
  selection.k2_t = SquaredCoefficientT(quadratic);
  if (quadratic.covariance.size() > 0) {
    selection.k2_t_threshold = internal::StudentTTwoSidedQuantile(kSquaredCoefficientAlpha / 3,
                                                                  quadratic.degrees_of_freedom);
  }
  if (!quadratic.crossval_rms) {
    return linear_alone("the quadratic model cannot be validated (" + quadratic.crossval_note +
                        ")");
  }

  // The linear fit on the positions the quadratic screening kept.
  selection.screened_with = ModelKind::kQuadratic;
  selection.positions_used = PositionsInFit(quadratic, readings.size());
  selection.linear = FitOnPositions(readings, linear_options, selection.positions_used, quadratic);
  if (!selection.linear.summary.converged()) {
    selection.reason = "the linear fit did not converge";
    return selection;
  }
  const std::optional<double>& lin = selection.linear.crossval_rms;
  const double quad = *quadratic.crossval_rms;
  if (!lin) {
    selection.reason = "the linear model cannot be validated (" + selection.linear.crossval_note +
                       "), so nothing shows the quadratic better";
    return selection;
  }

  const internal::Paired paired = internal::PairedImprovement(
      selection.linear.crossval_errors, quadratic.crossval_errors, selection.positions_used);
  const auto n = static_cast<int>(selection.positions_used.size());
  selection.improvement = paired.mean;
  selection.improvement_se = paired.se;
  const double z = internal::StudentTTwoSidedQuantile(2 * kHeldOutImprovementAlpha, n - 1);
  selection.improvement_threshold = z * paired.se;
  const double max_t = LargestAbsolute(selection.k2_t);
  const bool improves = selection.improvement > selection.improvement_threshold;
  const bool significant = max_t > selection.k2_t_threshold;
  // The numbers of both conditions, whichever decided.
  const std::string numbers =
      Format("held-out rms |f|-g %.4g (quadratic) against %.4g (linear)", quad, *lin) + " over " +
      std::to_string(n) + " positions; paired mean square improvement " +
      Format("%.3g +/- %.3g", paired.mean, paired.se) +
      Format(" (needs > %.3g, %.3g standard errors); ", selection.improvement_threshold, z) +
      (std::isnan(max_t)
           ? std::string("the squared coefficients have no standard errors")
           : Format("largest |k2/sigma| %.3g (needs > %.3g)", max_t, selection.k2_t_threshold));
  if (!improves) {
    selection.reason =
        "the quadratic model does not predict held-out positions better beyond sampling error: " +
        numbers;
  } else if (!significant) {
    selection.reason =
        "no squared coefficient is significant, though the quadratic model predicts held-out "
        "positions better beyond sampling error: " +
        numbers;
  } else {
    selection.chosen = ModelKind::kQuadratic;
    selection.reason =
        "it predicts held-out positions better beyond sampling error and a squared coefficient "
        "is significant: " +
        numbers;
  }
  return selection;
}

}  // namespace accelcal

namespace accelcal {

namespace {

// The Wald statistic of what `richer` adds to a `simpler` bias model (BiasModelStep::wald) and its
// degrees of freedom; NaN without a covariance or when the constraint's covariance is singular.
std::pair<double, int> DriftWald(const CalibrationResult& richer, const BiasModel& simpler) {
  const BiasDrift& drift = *richer.drift;
  const Eigen::Index J = drift.D.cols();
  const Eigen::Index P = drift.covariance.rows() - 3 * J;
  // The constraints on one axis' coefficients d_1 … d_J (d_0 = 0: the first knot's bias less
  // itself): all zero, or zero second differences of the knot biases (equally spaced knots).
  Eigen::MatrixXd A1;
  if (simpler.constant()) {
    A1 = Eigen::MatrixXd::Identity(J, J);
  } else {
    A1 = Eigen::MatrixXd::Zero(J - 1, J);
    for (Eigen::Index r = 0; r + 1 < J; ++r) {  // d_r − 2 d_{r+1} + d_{r+2}, d_0 = 0
      if (r > 0) A1(r, r - 1) = 1.0;
      A1(r, r) = -2.0;
      A1(r, r + 1) = 1.0;
    }
  }
  const auto q = static_cast<int>(3 * A1.rows());
  if (drift.covariance.size() == 0 || q == 0) return {std::nan(""), q};
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(q, P + 3 * J);
  Eigen::VectorXd d(3 * J);
  for (int i = 0; i < 3; ++i) {
    A.block(i * A1.rows(), P + i * J, A1.rows(), J) = A1;
    d.segment(i * J, J) = drift.D.row(i).transpose();
  }
  const Eigen::VectorXd a = A.rightCols(3 * J) * d;
  const Eigen::MatrixXd V = A * drift.covariance * A.transpose();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(V);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) {
    return {std::nan(""), q};
  }
  return {a.dot(ldlt.solve(a)), q};
}

}  // namespace

std::vector<BiasModel> BiasModelCandidates(int positions, ModelKind model) {
  std::vector<BiasModel> candidates = {BiasModel{}, BiasModel{BiasModelKind::kLinear, 0}};
  const int P = NumParameters(model);
  for (int K = 3; K <= 6 && positions - P - 3 * (K - 1) >= 10; ++K) {
    candidates.push_back(BiasModel{BiasModelKind::kSpline, K});
  }
  return candidates;
}

BiasModelSelection SelectBiasModel(const std::vector<Vec3>& readings, CalibrationOptions options) {
  BiasModelSelection selection;
  options.cross_validate = true;
  options.bias_basis.reset();
  CalibrationOptions current = options;
  current.bias_model = BiasModel{};
  selection.result = Calibrate(readings, current);
  if (!selection.result.summary.converged()) {
    selection.reason = "the fit with a constant bias did not converge";
    return selection;
  }
  if (options.position_times_s.size() != readings.size()) {
    selection.reason = "the positions have no times";
    return selection;
  }
  const std::vector<BiasModel> candidates =
      BiasModelCandidates(static_cast<int>(readings.size()), options.model);
  selection.reason = "no richer bias model was tried";
  std::string tried;  // each rejected candidate and why, for the reason
  for (std::size_t c = 1; c < candidates.size(); ++c) {
    BiasModelStep& step = selection.steps.emplace_back();
    step.simpler = current.bias_model;
    step.richer = candidates[c];
    const std::string richer_name = ToString(step.richer), simpler_name = ToString(step.simpler);
    const auto reject = [&](const std::string& why) {
      tried += (tried.empty() ? "" : "; ") + richer_name + " " + why;
    };
    CalibrationOptions richer_options = options;
    richer_options.bias_model = step.richer;
    std::optional<CalibrationResult> richer;
    try {
      richer = Calibrate(readings, richer_options);
    } catch (const DataError& e) {
      step.error = e.what();
    }
    if (richer && !richer->summary.converged()) {
      step.error = "did not converge: " + richer->summary.termination_message;
    } else if (richer && !richer->crossval_rms) {
      step.error = "cannot be validated: " + richer->crossval_note;
    }
    if (!step.error.empty()) {
      reject("cannot be compared (" + step.error + ")");
      continue;
    }
    step.positions_used = PositionsInFit(*richer, readings.size());
    const CalibrationResult simpler =
        FitOnPositions(readings, current, step.positions_used, *richer);
    if (!simpler.summary.converged() || !simpler.crossval_rms) {
      step.error = "the " + simpler_name + " bias on its positions " +
                   (simpler.summary.converged() ? "cannot be validated: " + simpler.crossval_note
                                                : std::string("did not converge"));
      reject("cannot be compared (" + step.error + ")");
      continue;
    }
    const internal::Paired paired = internal::PairedImprovement(
        simpler.crossval_errors, richer->crossval_errors, step.positions_used);
    const auto n = static_cast<int>(step.positions_used.size());
    step.simpler_rms = Rms(simpler.InFit(simpler.crossval_errors));
    step.richer_rms = *richer->crossval_rms;
    step.improvement = paired.mean;
    step.improvement_se = paired.se;
    const double z = internal::StudentTTwoSidedQuantile(2 * kHeldOutImprovementAlpha, n - 1);
    step.improvement_threshold = z * paired.se;
    std::tie(step.wald, step.wald_dof) = DriftWald(*richer, step.simpler);
    step.wald_threshold = internal::ChiSquareQuantile(kBiasDriftAlpha, step.wald_dof);
    const bool improves = step.improvement > step.improvement_threshold;
    const bool significant = step.wald > step.wald_threshold;
    step.accepted = improves && significant;
    const std::string numbers =
        Format(
            "held-out rms |f|-g %.4g (%s) against %.4g (%s) over %d positions; paired mean "
            "square improvement %.3g +/- %.3g (needs > %.3g, %.3g standard errors); ",
            step.richer_rms, richer_name.c_str(), step.simpler_rms, simpler_name.c_str(), n,
            paired.mean, paired.se, step.improvement_threshold, z) +
        (std::isnan(step.wald) ? std::string("its drift has no covariance")
                               : Format("Wald %.3g on %d degrees of freedom (needs > %.3g)",
                                        step.wald, step.wald_dof, step.wald_threshold));
    if (!step.accepted) {
      reject(!improves ? Format("does not predict held-out positions better than %s beyond "
                                "sampling error (%.3g against %.3g)",
                                simpler_name.c_str(), step.richer_rms, step.simpler_rms)
                       : std::string(step.simpler.constant()
                                         ? "has no significant drift"
                                         : "does not depart significantly from a linear drift") +
                             Format(" (Wald %.3g, needs > %.3g)", step.wald, step.wald_threshold));
      continue;
    }
    selection.chosen = step.richer;
    selection.result = std::move(*richer);
    current.bias_model = step.richer;
    selection.reason = "a " + richer_name + " bias predicts held-out positions better than " +
                       simpler_name + " beyond sampling error and " +
                       (step.simpler.constant() ? "its drift is significant: "
                                                : "departs significantly from a linear drift: ") +
                       numbers;
  }
  if (selection.chosen.constant()) {
    selection.reason = "no bias model that follows time passes the evidence rule: " + tried;
  } else if (!tried.empty()) {
    selection.reason += "; not " + tried;
  }
  return selection;
}

}  // namespace accelcal
