// Ingestion speed: parsing the Xsens recording (3.3 MB of text) and detecting its intervals.
#include <benchmark/benchmark.h>

#include "accelcal/log_reader.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {
namespace {

const std::string kXsens = std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/xsens_acc.mat";

void BM_ParseXsens(benchmark::State& state) {
  const std::string text = ReadFileToString(kXsens);
  for (auto _ : state) {
    const InputData d = ParseInput(text, kXsens, {});
    benchmark::DoNotOptimize(d.raw.samples.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * text.size()));
}
BENCHMARK(BM_ParseXsens)->Unit(benchmark::kMillisecond);

void BM_DetectXsens(benchmark::State& state) {
  const InputData d = ReadInput(kXsens, {});
  for (auto _ : state) {
    const StaticDetectionResult r = DetectStaticIntervals(d.raw, {});
    benchmark::DoNotOptimize(r.intervals.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * d.raw.samples.size()));
}
BENCHMARK(BM_DetectXsens)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace accelcal
