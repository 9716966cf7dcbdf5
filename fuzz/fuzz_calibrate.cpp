// libFuzzer harness: the whole calibration on parsed data. The bytes give the method, model and
// frame and up to 64 averaged readings (3 doubles each, any bit pattern). Accepted failure:
// DataError (unusable data, said why). A result is never NaN: a converged fit has finite
// parameters and covariance, a non-converged one says so.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "accelcal/calibrate.hpp"
#include "accelcal/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  using accelcal::SolverMethod;
  constexpr SolverMethod kMethods[] = {SolverMethod::kJoint,          SolverMethod::kTwoStep,
                                       SolverMethod::kNewtonLagrange, SolverMethod::kModulus,
                                       SolverMethod::kModulusNorm,    SolverMethod::kEllipsoid};
  const std::uint8_t control = data[0];
  accelcal::CalibrationOptions options;
  options.method = kMethods[control % 6];
  options.model =
      (control / 6) % 2 ? accelcal::ModelKind::kQuadratic : accelcal::ModelKind::kLinear;
  options.frame = (control / 12) % 2 ? accelcal::Frame::kZFirst : accelcal::Frame::kXFirst;
  options.joint.max_iterations = 50;  // bounded work per input
  options.two_step.max_sweeps = 200;
  std::vector<accelcal::Vec3> readings;
  for (std::size_t at = 1; at + 24 <= size && readings.size() < 64; at += 24) {
    double v[3];
    std::memcpy(v, data + at, sizeof v);
    readings.emplace_back(v[0], v[1], v[2]);
  }
  if (options.Validate()) return 0;  // an unsupported combination is a usage error
  try {
    const accelcal::CalibrationResult r = accelcal::Calibrate(readings, options);
    if (r.summary.converged()) {
      const auto& p = r.params;
      if (!p.K.allFinite() || !p.bias.allFinite() || !p.k2.allFinite()) std::abort();
      if (r.covariance.size() > 0 && !r.covariance.allFinite()) std::abort();
      for (const accelcal::Vec3& c : r.directions) {
        if (!c.allFinite()) std::abort();
      }
    }
  } catch (const accelcal::DataError&) {
  }
  return 0;
}
