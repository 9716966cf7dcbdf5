// The streamed overlapping Allan variance (issue 19): samples per second into an accumulator,
// which bounds the time of a 24-hour 400 Hz log's three axes (3 × 34.6 M samples).
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "accelcal/allan.hpp"

namespace accelcal {
namespace {

void BM_AllanAccumulate(benchmark::State& state) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> block(1 << 16);
  for (double& v : block) v = normal(rng);
  AllanOptions options;
  options.sample_period_s = 1.0 / 400;
  options.full_overlap_up_to = static_cast<std::uint64_t>(state.range(0));
  AllanAccumulator accumulator(options);
  for (auto _ : state) accumulator.Add(block.data(), block.size());
  benchmark::DoNotOptimize(accumulator.Points());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(block.size()));
}
BENCHMARK(BM_AllanAccumulate)->Arg(8)->Arg(32)->Arg(128);

}  // namespace
}  // namespace accelcal
