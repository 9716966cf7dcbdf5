// Solver speed on paper 000's Table-3 problem (18 positions, Table-4 noise).
#include <benchmark/benchmark.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/design.hpp"
#include "accelcal/ellipsoid_fit.hpp"
#include "accelcal/simulate.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal {
namespace {

std::vector<Vec3> Table3Readings(ModelKind model) {
  ModelParameters truth = Yang2012Truth();
  if (model == ModelKind::kLinear) truth.k2.setZero();
  Vec3 sigma;
  for (int i = 0; i < 3; ++i) sigma(i) = truth.K.row(i).norm() * kYang2012PositionSigma_ms2;
  return SimulatePositions(truth, kYang2012Gravity_ms2, Yang18Directions(), sigma, 42);
}

// Times Calibrate() and reports the solver's iterations as a counter.
void TimeCalibrate(benchmark::State& state, const std::vector<Vec3>& readings,
                   const CalibrationOptions& options) {
  int iterations = 0;
  for (auto _ : state) {
    const CalibrationResult r = Calibrate(readings, options);
    iterations = r.summary.iterations;
    benchmark::DoNotOptimize(r.params.K(0, 0));
  }
  state.counters["solver_iterations"] = iterations;
}

void BM_Calibrate(benchmark::State& state, ModelKind model, SolverMethod method) {
  CalibrationOptions options;
  options.model = model;
  options.method = method;
  options.gravity = kYang2012Gravity_ms2;
  TimeCalibrate(state, Table3Readings(model), options);
}

BENCHMARK_CAPTURE(BM_Calibrate, joint_quadratic_18, ModelKind::kQuadratic, SolverMethod::kJoint)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Calibrate, joint_linear_18, ModelKind::kLinear, SolverMethod::kJoint)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Calibrate, two_step_quadratic_18, ModelKind::kQuadratic,
                  SolverMethod::kTwoStep)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Calibrate, two_step_linear_18, ModelKind::kLinear, SolverMethod::kTwoStep)
    ->Unit(benchmark::kMicrosecond);

// Paper 001 §4.1: 300 positions, σ = 0.1 g, linear model.
void BM_SunXu300(benchmark::State& state, SolverMethod method) {
  const std::vector<Vec3> readings = SimulateLinearPositions(
      SunXu2020Ta(), SunXu2020Ba(), SunXu2020Directions(300, 1), kSunXu2020Sigma_g, 1001);
  CalibrationOptions options;
  options.method = method;
  options.gravity = 1.0;
  TimeCalibrate(state, readings, options);
}

BENCHMARK_CAPTURE(BM_SunXu300, newton_lagrange, SolverMethod::kNewtonLagrange)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SunXu300, joint, SolverMethod::kJoint)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SunXu300, modulus, SolverMethod::kModulus)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SunXu300, ellipsoid, SolverMethod::kEllipsoid)->Unit(benchmark::kMicrosecond);

// Where the time of a 300-position Calibrate() goes: the Newton-Lagrange iteration alone (from the
// ellipsoid start, as Calibrate runs it), and the observability/covariance information at the end.
void BM_SunXu300Stage(benchmark::State& state, bool solver) {
  const std::vector<Vec3> readings = SimulateLinearPositions(
      SunXu2020Ta(), SunXu2020Ba(), SunXu2020Directions(300, 1), kSunXu2020Sigma_g, 1001);
  CalibrationOptions options;
  options.method = SolverMethod::kNewtonLagrange;
  options.gravity = 1.0;
  const internal::Problem problem{readings, options.gravity, options.model};
  const ModelParameters start = FitEllipsoid(readings, options.gravity).params;
  const std::vector<Vec3> dirs = internal::DirectionsFromParams(problem, start);
  const internal::SolverOutput solved =
      internal::SolveNewtonLagrange(problem, start, dirs, options);
  for (auto _ : state) {
    if (solver) {
      benchmark::DoNotOptimize(
          internal::SolveNewtonLagrange(problem, start, dirs, options).params.K(0, 0));
    } else {
      benchmark::DoNotOptimize(
          internal::ComputeInformation(problem, solved.params, solved.dirs).rcond);
    }
  }
}
BENCHMARK_CAPTURE(BM_SunXu300Stage, newton_lagrange_solver_only, true)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SunXu300Stage, information_only, false)->Unit(benchmark::kMicrosecond);

// One Newton-Lagrange step on the 300 positions with each build of the per-position kernel (packing
// the positions into the kernel's blocks included): what AVX gains over the baseline x86-64.
void BM_SunXu300Step(benchmark::State& state, internal::KernelIsa isa) {
  if (!internal::KernelAvailable(isa)) {
    state.SkipWithError("this CPU or build has no such kernel");
    return;
  }
  const std::vector<Vec3> readings = SimulateLinearPositions(
      SunXu2020Ta(), SunXu2020Ba(), SunXu2020Directions(300, 1), kSunXu2020Sigma_g, 1001);
  const internal::Problem problem{readings, 1.0, ModelKind::kLinear};
  const ModelParameters start = FitEllipsoid(readings, 1.0).params;
  const std::vector<Vec3> dirs = internal::DirectionsFromParams(problem, start);
  const std::vector<double> lambda(dirs.size(), 0.0);
  const internal::Vec9 theta = Pack(start, ModelKind::kLinear);
  internal::NewtonLagrangeStep step;
  for (auto _ : state) {
    internal::ComputeNewtonLagrangeStep(problem, theta, dirs, lambda, &step, isa);
    benchmark::DoNotOptimize(step.d_theta(0));
  }
}
BENCHMARK_CAPTURE(BM_SunXu300Step, baseline, internal::KernelIsa::kBaseline)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SunXu300Step, avx, internal::KernelIsa::kAvx)->Unit(benchmark::kMicrosecond);

// The ellipsoid method on the 18 positions of Table 3 (linear device): the whole Calibrate() call,
// with the data checks and the observability check at the solution.
BENCHMARK_CAPTURE(BM_Calibrate, ellipsoid_linear_18, ModelKind::kLinear, SolverMethod::kEllipsoid)
    ->Unit(benchmark::kMicrosecond);

// The fits alone, algebraic and constrained (Li & Griffiths), on 18 positions.
void BM_FitEllipsoid(benchmark::State& state, bool constrained) {
  const std::vector<Vec3> readings = Table3Readings(ModelKind::kLinear);
  for (auto _ : state) {
    const EllipsoidFitResult fit = constrained
                                       ? FitEllipsoidConstrained(readings, kYang2012Gravity_ms2)
                                       : FitEllipsoid(readings, kYang2012Gravity_ms2);
    benchmark::DoNotOptimize(fit.params.K(0, 0));
  }
}
BENCHMARK_CAPTURE(BM_FitEllipsoid, algebraic_18, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_FitEllipsoid, constrained_18, true)->Unit(benchmark::kMicrosecond);

// The Cramér-Rao bound of 18 planned positions for the Table-3 device (issue 4: <= 1 ms).
void BM_Design18(benchmark::State& state) {
  const ModelParameters device = Yang2012Truth();
  const std::vector<Vec3> directions = Yang18Directions();
  for (auto _ : state) {
    const PlannedUncertainty planned = PredictUncertainty(
        device, ModelKind::kQuadratic, kYang2012Gravity_ms2, directions, Vec3::Constant(0.5));
    benchmark::DoNotOptimize(planned.rcond);
  }
}
BENCHMARK(BM_Design18)->Unit(benchmark::kMicrosecond);

// D-optimal choice of 18 of 500 random candidates (issue 4: <= 1 s).
void BM_DOptimal18Of500(benchmark::State& state) {
  const ModelParameters device = Yang2012Truth();
  const std::vector<Vec3> candidates = RandomDirections(500, 1);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ChooseDOptimal(device, ModelKind::kQuadratic, kYang2012Gravity_ms2,
                                            candidates, Vec3::Constant(0.5), 18)
                                 .size());
  }
}
BENCHMARK(BM_DOptimal18Of500)->Unit(benchmark::kMillisecond);

// A-optimal choice of 18 of 500 (the D-optimal start and 8 random restarts).
void BM_AOptimal18Of500(benchmark::State& state) {
  const ModelParameters device = Yang2012Truth();
  const std::vector<Vec3> candidates = RandomDirections(500, 1);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ChooseAOptimal(device, ModelKind::kQuadratic, kYang2012Gravity_ms2,
                                            candidates, Vec3::Constant(0.5), 18)
                                 .size());
  }
}
BENCHMARK(BM_AOptimal18Of500)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace accelcal
