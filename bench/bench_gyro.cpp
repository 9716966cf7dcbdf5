// The gyroscope's calibration (issue 18): the integration of one turn's calibrated rates, with and
// without its parameter Jacobian, per sample.
#include <benchmark/benchmark.h>

#include "accelcal/gyro_model.hpp"

namespace accelcal {
namespace {

// A 4.3 s turn at 100 Hz (the Xsens recording's typical turn): about 90° about a tilted axis.
struct Turn {
  std::vector<double> t_s;
  std::vector<Vec3> raw, f;
};
Turn MakeTurn(std::size_t samples) {
  Turn turn;
  const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
  for (std::size_t k = 0; k < samples; ++k) {
    const double s = static_cast<double>(k) / static_cast<double>(samples - 1);
    turn.t_s.push_back(0.01 * static_cast<double>(k));
    turn.raw.push_back(Vec3(32768, 32466, 32485) + 4770.0 * 0.73 * 4 * s * (1 - s) * axis);
    turn.f.push_back(Vec3(0, 0, 9.81));
  }
  return turn;
}

void BM_IntegrateTurn(benchmark::State& state, bool jacobian, GyroModelKind kind) {
  const Turn turn = MakeTurn(static_cast<std::size_t>(state.range(0)));
  GyroParameters params;
  params.K << 4782, -42, -54, -26, 4765, 151, -75, 108, 4769;
  params.bias = Vec3(32770, 32451, 32509);
  params.G << 0.08, 0.3, 0.66, -1.3, 0.04, 0.84, -0.73, -0.8, 0.25;
  Eigen::MatrixXd J;
  for (auto _ : state) {
    benchmark::DoNotOptimize(IntegrateCalibratedRate(params, kind, turn.t_s, turn.raw, turn.f,
                                                     RateInterpolation::kTrapezoidal,
                                                     jacobian ? &J : nullptr));
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK_CAPTURE(BM_IntegrateTurn, rotation, false, GyroModelKind::kGSensitive)->Arg(430);
BENCHMARK_CAPTURE(BM_IntegrateTurn, with_jacobian, true, GyroModelKind::kGSensitive)->Arg(430);

}  // namespace
}  // namespace accelcal
