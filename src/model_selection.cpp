#include "accelcal/model_selection.hpp"

#include <cmath>
#include <cstdio>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"

namespace accelcal {

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

std::string Format(const char* format, double a, double b) {
  char buf[200];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

}  // namespace

ModelSelection SelectModel(const std::vector<Vec3>& readings, CalibrationOptions options) {
  ModelSelection selection;
  options.cross_validate = true;
  options.model = ModelKind::kLinear;
  selection.linear = Calibrate(readings, options);
  if (!selection.linear.summary.converged()) {
    selection.reason = "the linear fit did not converge";
    return selection;
  }
  options.model = ModelKind::kQuadratic;
  if (options.initial_params) options.initial_params->k2.setZero();
  try {
    selection.quadratic = Calibrate(readings, options);
  } catch (const DataError& e) {
    selection.quadratic_error = e.what();
  }
  if (selection.quadratic && !selection.quadratic->summary.converged()) {
    selection.quadratic_error =
        "did not converge: " + selection.quadratic->summary.termination_message;
    selection.quadratic.reset();
  }
  if (!selection.quadratic) {
    selection.reason = "the quadratic model cannot be fitted (" + selection.quadratic_error + ")";
    return selection;
  }
  selection.k2_t = SquaredCoefficientT(*selection.quadratic);
  const std::optional<double>& lin = selection.linear.crossval_rms;
  const std::optional<double>& quad = selection.quadratic->crossval_rms;
  if (!quad) {
    selection.reason =
        "the quadratic model cannot be validated (" + selection.quadratic->crossval_note + ")";
  } else if (!lin) {
    selection.reason = "the linear model cannot be validated (" + selection.linear.crossval_note +
                       "), so nothing shows the quadratic better";
  } else if (*quad < *lin) {
    selection.chosen = ModelKind::kQuadratic;
    selection.reason =
        Format("it predicts held-out positions better (rms |f|-g %.4g against %.4g)", *quad, *lin);
  } else {
    selection.reason = Format(
        "the quadratic model does not predict held-out positions better (rms |f|-g "
        "%.4g against %.4g for linear)",
        *quad, *lin);
  }
  return selection;
}

}  // namespace accelcal
