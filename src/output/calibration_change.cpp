// CompareCalibrations (calibration_change.hpp): one χ² per sensor of the parameters' difference
// against the sum of the two calibrations' covariances.
#include "accelcal/calibration_change.hpp"

#include <cmath>

#include <Eigen/Cholesky>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/gyro_model.hpp"
#include "accelcal/model.hpp"
#include "accelcal/sensor_parameters.hpp"
#include "core/text_format.hpp"
#include "statistics/student_t.hpp"

namespace accelcal {
namespace {

// Δ = later − earlier against C = C_earlier + C_later; a C that is not positive definite (a
// parameter held fixed in both) is compared on its diagonal's positive entries only.
ParameterChange Change(const Eigen::VectorXd& earlier, const Eigen::VectorXd& later,
                       const Eigen::MatrixXd& c, const std::vector<std::string>& names,
                       std::optional<double> noise_dof) {
  ParameterChange change;
  const Eigen::VectorXd delta = later - earlier;
  if (!delta.allFinite() || !c.allFinite()) {
    throw DataError("a parameter, its difference or its covariance is not a finite number");
  }
  std::vector<int> kept;
  for (int i = 0; i < delta.size(); ++i) {
    const double var = c(i, i);
    change.z.emplace_back(names[i], var > 0 ? delta(i) / std::sqrt(var) : 0.0);
    if (var > 0) kept.push_back(i);
  }
  const int n = static_cast<int>(kept.size());
  Eigen::VectorXd d(n);
  Eigen::MatrixXd ck(n, n);
  for (int a = 0; a < n; ++a) {
    d(a) = delta(kept[a]);
    for (int b = 0; b < n; ++b) ck(a, b) = c(kept[a], kept[b]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(ck);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
    throw DataError("the calibrations' summed covariance is not positive definite");
  }
  change.chi2 = d.dot(ldlt.solve(d));
  change.dof = n;
  if (n == 0) return change;
  if (noise_dof) {
    // Covariances scaled by noise levels estimated from the fits' residuals: chi2 / n against
    // F(n, ν) rather than chi2 against χ²_n, whose tail would flag unchanged units too often
    // (ν = 9 for 18 positions: 11 of 100 unchanged units at p < 0.05 by χ², about 5 by F).
    change.noise_dof = noise_dof;
    change.p = internal::FisherFSurvival(change.chi2 / n, n, *noise_dof);
  } else {
    change.p = internal::ChiSquareSurvival(change.chi2, n);
  }
  return change;
}

}  // namespace

CalibrationChange CompareCalibrations(const LoadedCalibration& earlier,
                                      const LoadedCalibration& later,
                                      const ChangeOptions& options) {
  const auto refuse = [](const std::string& what, const std::string& a, const std::string& b) {
    throw DataError("the calibrations cannot be compared: " + what + " differ (" + a + ", then " +
                    b + ")");
  };
  if (earlier.model != later.model) {
    refuse("their models", std::string(ToString(earlier.model)),
           std::string(ToString(later.model)));
  }
  if (earlier.frame != later.frame) {
    refuse("their frames", std::string(ToString(earlier.frame)),
           std::string(ToString(later.frame)));
  }
  if (earlier.unit != later.unit) {
    refuse("their specific-force units", std::string(ToString(earlier.unit)),
           std::string(ToString(later.unit)));
  }
  if (earlier.raw_unit != later.raw_unit)
    refuse("their raw units", earlier.raw_unit, later.raw_unit);
  const int n = static_cast<int>(ParameterSlots(later.model, later.frame).size());
  for (const LoadedCalibration* cal : {&earlier, &later}) {
    if (cal->covariance.rows() != n || cal->covariance.cols() != n) {
      throw DataError(
          "the calibrations cannot be compared: one has no covariance (a baseline method such as "
          "ellipsoid or modulus)");
    }
  }
  if (earlier.thermal.has_value() != later.thermal.has_value()) {
    throw DataError(
        "the calibrations cannot be compared: one follows temperature, the other does not");
  }
  if (earlier.thermal &&
      std::abs(earlier.thermal->params.t_ref_c - later.thermal->params.t_ref_c) > 0.5) {
    throw DataError(internal::Format(
        "the calibrations cannot be compared: their reference temperatures differ (%.1f and "
        "%.1f degC), and so do the parameters they give",
        earlier.thermal->params.t_ref_c, later.thermal->params.t_ref_c));
  }
  const std::vector<SensorParameter> earlier_list =
      ListParameters(earlier.params, earlier.model, earlier.frame);
  const std::vector<SensorParameter> list = ListParameters(later.params, later.model, later.frame);
  const std::vector<std::string> names = ParameterNames(list);
  CalibrationChange change;
  if (later.thermal) {
    change.notes.push_back(
        "the parameters compared at T_ref; their temperature coefficients are not compared");
  }
  // The two noise levels' degrees of freedom, summed: each covariance's scale estimated from its
  // own fit; a level from the samples counts as known.
  std::optional<double> noise_dof;
  if (earlier.covariance_dof || later.covariance_dof) {
    noise_dof = earlier.covariance_dof.value_or(0) + later.covariance_dof.value_or(0);
  }
  Eigen::MatrixXd c = earlier.covariance + later.covariance;
  if (options.bias_repeatability) {
    // The bias's turn-on repeatability q in raw units: q times the axis' scale factor.
    for (int i = 0; i < n; ++i) {
      const SensorParameter& p = list[static_cast<std::size_t>(i)];
      if (p.role != ParameterRole::kOffset) continue;
      const double q = (*options.bias_repeatability)(p.axis) * later.params.K.row(p.axis).norm();
      c(i, i) += 2 * q * q;
    }
  }
  const Eigen::VectorXd before = ParameterValues(earlier_list), after = ParameterValues(list);
  change.accelerometer = Change(before, after, c, names, noise_dof);
  // The same over the scale-and-misalignment slots, and over the bias's.
  for (const bool bias : {false, true}) {
    std::vector<int> idx;
    for (int i = 0; i < n; ++i) {
      if ((list[static_cast<std::size_t>(i)].role == ParameterRole::kOffset) == bias) {
        idx.push_back(i);
      }
    }
    const int m = static_cast<int>(idx.size());
    Eigen::VectorXd ai(m), bi(m);
    Eigen::MatrixXd ci(m, m);
    std::vector<std::string> ni;
    for (int r = 0; r < m; ++r) {
      ai(r) = before(idx[r]);
      bi(r) = after(idx[r]);
      ni.push_back(names[static_cast<std::size_t>(idx[r])]);
      for (int s = 0; s < m; ++s) ci(r, s) = c(idx[r], idx[s]);
    }
    (bias ? change.accelerometer_bias : change.accelerometer_scale) =
        Change(ai, bi, ci, ni, noise_dof);
  }
  change.compatible = change.accelerometer.p >= kChangeP;
  if (earlier.gyroscope && later.gyroscope) {
    const auto& a = *earlier.gyroscope;
    const auto& b = *later.gyroscope;
    const int m = NumGyroParameters(b.model);
    if (a.model != b.model) {
      change.notes.push_back("the gyroscopes' models differ (" + std::string(ToString(a.model)) +
                             ", then " + std::string(ToString(b.model)) + "): not compared");
    } else if (a.raw_unit != b.raw_unit) {
      change.notes.push_back("the gyroscopes' raw units differ: not compared");
    } else if (a.covariance.rows() != m || b.covariance.rows() != m) {
      change.notes.push_back("a gyroscope has no covariance: not compared");
    } else {
      const std::vector<SensorParameter> a_list = ListParameters(a.params, a.model),
                                         b_list = ListParameters(b.params, b.model);
      change.gyroscope =
          Change(ParameterValues(a_list), ParameterValues(b_list), a.covariance + b.covariance,
                 ParameterNames(b_list),
                 std::nullopt);  // the gyroscope's noise from its turns' scatter: as known
      change.compatible = change.compatible && change.gyroscope->p >= kChangeP;
    }
  } else if (earlier.gyroscope || later.gyroscope) {
    change.notes.push_back("only one of them has a gyroscope: not compared");
  }
  return change;
}

}  // namespace accelcal
