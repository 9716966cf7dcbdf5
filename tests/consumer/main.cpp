// Calibrates paper 000's noise-free Table-3 problem through the installed library.
#include <cstdio>

#include <accelcal/calibrate.hpp>
#include <accelcal/simulate.hpp>

int main() {
  const accelcal::ModelParameters truth = accelcal::Yang2012Truth();
  const auto readings = accelcal::SimulatePositions(truth, 9.8, accelcal::Yang18Directions(),
                                                    accelcal::Vec3::Zero(), 1);
  accelcal::CalibrationOptions options;
  options.model = accelcal::ModelKind::kQuadratic;
  options.gravity = 9.8;
  const accelcal::CalibrationResult r = accelcal::Calibrate(readings, options);
  const double error = (r.params.K - truth.K).norm() / truth.K.norm();
  std::printf("%s\nrelative error of K: %.3g\n", r.summary.BriefReport().c_str(), error);
  return r.summary.converged() && error < 1e-9 ? 0 : 1;
}
