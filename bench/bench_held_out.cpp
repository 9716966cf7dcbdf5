// Held-out (leave-one-position-out) validation of a converged fit: CrossValidate from the
// expansion of the full fit (held_out.hpp), against the m refits it replaces.
#include <benchmark/benchmark.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/simulate.hpp"
#include "statistics/held_out.hpp"

namespace accelcal {
namespace {

// Yang's device (linear, or with its squared coefficients) at m random positions, noise 1e-3 of
// each axis' signal (a MEMS positions file: ~0.01 m/s² per position).
std::vector<Vec3> Readings(ModelKind model, int m) {
  ModelParameters truth = Yang2012Truth();
  if (model == ModelKind::kLinear) truth.k2.setZero();
  Vec3 sigma;
  for (int i = 0; i < 3; ++i) sigma(i) = truth.K(i, i) * kYang2012Gravity_ms2 * 1e-3;
  return SimulatePositions(truth, kYang2012Gravity_ms2, RandomDirections(m, 1), sigma, 2);
}

// Times CrossValidate on a converged fit; counters: how the numbers were obtained.
void BM_CrossValidate(benchmark::State& state, ModelKind model, SolverMethod method, bool refits) {
  const std::vector<Vec3> readings = Readings(model, static_cast<int>(state.range(0)));
  CalibrationOptions options;
  options.model = model;
  options.method = method;
  options.gravity = kYang2012Gravity_ms2;
  const CalibrationResult full = Calibrate(readings, options);
  internal::HeldOutPaths paths;
  for (auto _ : state) {
    CalibrationResult r = full;
    if (refits) {
      internal::CrossValidateByRefits(readings, options, &r);
    } else {
      paths = {};
      internal::HeldOutErrors(
          readings, options,
          [&](std::size_t k) { return internal::RefitWithout(readings, options, full, k); }, &r,
          &paths);
    }
    benchmark::DoNotOptimize(r.crossval_rms);
  }
  state.counters["from_expansion"] = paths.from_expansion;
  state.counters["corrected"] = paths.corrected;
  state.counters["refitted"] = paths.refitted;
}

BENCHMARK_CAPTURE(BM_CrossValidate, joint_linear, ModelKind::kLinear, SolverMethod::kJoint, false)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CrossValidate, joint_quadratic, ModelKind::kQuadratic, SolverMethod::kJoint,
                  false)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CrossValidate, modulus, ModelKind::kLinear, SolverMethod::kModulus, false)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_CrossValidate, ellipsoid, ModelKind::kLinear, SolverMethod::kEllipsoid, false)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond);
// The m refits CrossValidate made before (quadratic in m).
BENCHMARK_CAPTURE(BM_CrossValidate, joint_linear_refits, ModelKind::kLinear, SolverMethod::kJoint,
                  true)
    ->Arg(1000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace
}  // namespace accelcal
