#include "accelcal/compare.hpp"

#include <cmath>
#include <stdexcept>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "statistics/fit.hpp"
#include "statistics/outliers.hpp"

namespace accelcal {

ParameterErrors SunXuErrors(const ModelParameters& reference, const ModelParameters& estimate) {
  const Mat33 T = ChangeFrame(reference.K, Frame::kZFirst).K;
  const Mat33 Tc = ChangeFrame(estimate.K, Frame::kZFirst).K;
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) sum += (T(i, j) - Tc(i, j)) * (T(i, j) - Tc(i, j));
  }
  return {std::sqrt(sum) / 6.0 * 100.0, (reference.bias - estimate.bias).norm() / 3.0 * 100.0};
}

std::vector<SolverMethod> MethodsFor(ModelKind model) {
  if (model == ModelKind::kQuadratic) return {SolverMethod::kJoint, SolverMethod::kTwoStep};
  return {SolverMethod::kJoint,   SolverMethod::kTwoStep,     SolverMethod::kNewtonLagrange,
          SolverMethod::kModulus, SolverMethod::kModulusNorm, SolverMethod::kEllipsoid};
}

namespace {

// A converged fit, or the reason there is none.
std::optional<std::string> Fit(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                               CalibrationResult* result) {
  try {
    *result = Calibrate(readings, options);
  } catch (const DataError& e) {
    return std::string(e.what());
  }
  if (!result->summary.converged()) {
    return "did not converge: " + result->summary.termination_message;
  }
  return std::nullopt;
}

// Held-out figures from Calibrate's cross-validation, its refits started from this method's fit.
void LeaveOneOut(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                 MethodComparison* out) {
  CrossValidate(readings, options, &out->result);
  out->leave_one_out_rms = out->result.crossval_rms;
  if (!out->result.crossval_rms) out->leave_one_out_error = out->result.crossval_note;
}

// An earlier maximum-likelihood result at the same optimum as `c` (parameters equal to 1e-8 of
// the largest), whose held-out figures it can share, or nullptr.
const MethodComparison* SameMaximumLikelihoodOptimum(const std::vector<MethodComparison>& done,
                                                     const MethodComparison& c) {
  if (!IsMaximumLikelihood(c.method)) return nullptr;
  const Eigen::VectorXd theta = Pack(c.result.params, c.result.model);
  for (const MethodComparison& d : done) {
    if (d.error || !IsMaximumLikelihood(d.method) || d.leave_one_out_from) continue;
    const Eigen::VectorXd other = Pack(d.result.params, d.result.model);
    if ((theta - other).cwiseAbs().maxCoeff() <= 1e-8 * theta.cwiseAbs().maxCoeff()) return &d;
  }
  return nullptr;
}

// Screens the positions once with the maximum-likelihood fit and `base.outliers`; fills the
// comparison's positions and findings and returns the readings (and sigmas) every method gets.
CalibrationOptions ScreenOnce(const std::vector<Vec3>& readings, const CalibrationOptions& base,
                              Comparison* out, std::vector<Vec3>* used) {
  CalibrationOptions shared = base;
  shared.outliers.policy = OutlierPolicy::kOff;
  shared.cross_validate = false;
  std::vector<bool> excluded(readings.size(), false);
  if (base.outliers.policy != OutlierPolicy::kOff) {
    CalibrationOptions screen = base;
    screen.method = SolverMethod::kJoint;
    screen.cross_validate = false;
    try {
      const CalibrationResult fit = Calibrate(readings, screen);
      out->outliers = fit.outliers;
      out->outlier_note = fit.outlier_note;
      for (std::size_t k = 0; k < readings.size(); ++k) excluded[k] = fit.excluded(k);
      if (!fit.summary.converged()) {
        out->outlier_note = "not screened: the maximum-likelihood fit did not converge";
      }
    } catch (const DataError& e) {
      out->outlier_note = std::string("not screened: ") + e.what();
    }
  }
  if (!base.reading_sigmas.empty()) shared.reading_sigmas.clear();
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (excluded[k]) continue;
    out->positions_used.push_back(static_cast<int>(k));
    used->push_back(readings[k]);
    if (!base.reading_sigmas.empty()) shared.reading_sigmas.push_back(base.reading_sigmas[k]);
  }
  return shared;
}

}  // namespace

Comparison CompareMethods(const std::vector<Vec3>& all_readings, const CompareOptions& options) {
  if (auto why = options.base.Validate()) throw OptionError(*why);
  internal::CheckReadingSigmas(options.base.reading_sigmas, all_readings.size());
  const std::vector<SolverMethod> methods =
      options.methods.empty() ? MethodsFor(options.base.model) : options.methods;
  Comparison comparison;
  std::vector<Vec3> readings;
  const CalibrationOptions shared = ScreenOnce(all_readings, options.base, &comparison, &readings);
  std::vector<MethodComparison>& out = comparison.methods;
  for (SolverMethod method : methods) {
    CalibrationOptions o = shared;
    o.method = method;
    if (auto why = o.Validate()) throw OptionError(*why);
    MethodComparison c;
    c.method = method;
    c.error = Fit(readings, o, &c.result);
    std::vector<double> errors;
    if (!c.error) {
      // The result over all positions, as Calibrate gives it: the screened-out ones marked.
      internal::SpreadOverAllPositions(all_readings, comparison.positions_used, {}, &c.result);
      c.result.outliers = comparison.outliers;
      c.result.outlier_note = comparison.outlier_note;
      errors = GravityNormErrors(c.result.params, readings, o.gravity);
      for (std::size_t k = 0; k < errors.size() && !c.error; ++k) {
        if (!std::isfinite(errors[k])) {
          c.error = "position " + std::to_string(comparison.positions_used[k] + 1) +
                    " lies outside the range of the fit";
        }
      }
    }
    if (!c.error) {
      c.gravity_norm_rms = Rms(errors);
      double sum = 0, sum2 = 0;
      for (double e : errors) {
        const double q = std::pow((e + o.gravity) / o.gravity, 2);  // |f|²/g²
        sum += q;
        sum2 += q * q;
      }
      const double n = static_cast<double>(errors.size());
      c.modular_square_mean = sum / n;
      c.modular_square_std = std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1)));
      if (options.reference) c.against_reference = SunXuErrors(*options.reference, c.result.params);
      if (options.leave_one_out) {
        const MethodComparison* same = SameMaximumLikelihoodOptimum(out, c);
        if (same != nullptr) {
          c.leave_one_out_rms = same->leave_one_out_rms;
          c.leave_one_out_error = same->leave_one_out_error;
          c.leave_one_out_from = same->method;
        } else {
          // On all readings: the screened-out positions are held out of every refit and the
          // notes number positions as the input does.
          LeaveOneOut(all_readings, o, &c);
        }
      }
    }
    out.push_back(std::move(c));
  }
  return comparison;
}

}  // namespace accelcal
