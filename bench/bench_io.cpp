// Ingestion speed: parsing the Xsens recording (3.3 MB of text), detecting its intervals, and the
// SHA-256 of its bytes that a calibration file's provenance records (on the CPU's SHA extensions
// when it has them, and the portable block function).
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <thread>

#include <benchmark/benchmark.h>

#include "accelcal/log_reader.hpp"
#include "accelcal/mcap_writer.hpp"
#include "accelcal/native_log.hpp"
#include "accelcal/rosbag_writer.hpp"
#include "accelcal/sha256.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/static_detection.hpp"
#include "accelcal/ulog_writer.hpp"

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

// A PX4 ULog (issue 20: >= 500 MB/s): PX4's flight log (0.9 MB, 60 topics) parsed in memory,
// its one IMU stream at 200 Hz kept (argument 1: sensor_combined chosen) or every stream only
// counted (0: InspectLog's pass, on the file); and a simulated session (5.6 MB, one stream, every
// message kept), from the file with its SHA-256.
const std::string kULog = std::string(ACCELCAL_DATA_DIR) + "/px4-ulog/sample_log_small.ulg";
void BM_ParsePx4ULog(benchmark::State& state) {
  const std::string bytes = ReadFileToString(kULog);
  ReadOptions options;
  options.topic = "sensor_combined";
  for (auto _ : state) {
    if (state.range(0) != 0) {
      const InputData d = ParseInput(bytes, kULog, options);
      benchmark::DoNotOptimize(d.raw.samples.data());
    } else {
      const LogInventory log = InspectLog(kULog);
      benchmark::DoNotOptimize(log.streams.data());
    }
  }
  state.SetLabel(state.range(0) != 0 ? "sensor_combined kept" : "inspect (file)");
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
}
BENCHMARK(BM_ParsePx4ULog)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_ReadSimulatedULog(benchmark::State& state) {
  const std::string path = "/tmp/accelcal_bench_session.ulg";
  {
    // yang2012's 18 positions, 60 s each and 4 s turns, at 100 Hz: 115 200 messages.
    std::FILE* f = std::fopen(path.c_str(), "wb");
    const ULogImuWriter writer;
    const std::string header = writer.Header();
    std::fwrite(header.data(), 1, header.size(), f);
    RawLogSimulation sim;
    SimulateRawLog(Yang2012Truth(), 9.80665, Yang18Directions(), sim, [&](double t, const Vec3& p) {
      const std::string m = writer.Accel(static_cast<std::uint64_t>(std::llround(t * 1e6)), p);
      std::fwrite(m.data(), 1, m.size(), f);
    });
    std::fclose(f);
  }
  ReadOptions options;
  options.fingerprint = true;
  std::size_t bytes = 0;
  for (auto _ : state) {
    const InputData d = ReadInput(path, options);
    bytes = d.bytes;
    benchmark::DoNotOptimize(d.raw.samples.data());
  }
  std::remove(path.c_str());
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
}
BENCHMARK(BM_ReadSimulatedULog)->Unit(benchmark::kMillisecond)->UseRealTime();

// ROS (issue 20: >= 500 MB/s): the same simulated session (115 200 sensor_msgs/Imu messages) as
// ROS 2 records it in MCAP (argument: 0 uncompressed chunks, 1 lz4, 2 zstd) and as ROS 1 records
// it in a bag of uncompressed chunks (written here, as the specification lays one out), each read
// from the file with its SHA-256: bytes per second of the file, and of the messages decoded.
std::string WriteSession(const std::string& path,
                         const std::function<std::string(std::uint64_t ns, const Vec3& a)>& sample,
                         const std::string& head, const std::function<std::string()>& tail) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  std::fwrite(head.data(), 1, head.size(), f);
  RawLogSimulation sim;
  SimulateRawLog(Yang2012Truth(), 9.80665, Yang18Directions(), sim, [&](double t, const Vec3& p) {
    const std::string m =
        sample(1700000000000000000ull + static_cast<std::uint64_t>(std::llround(t * 1e9)), p);
    std::fwrite(m.data(), 1, m.size(), f);
  });
  const std::string end = tail();
  std::fwrite(end.data(), 1, end.size(), f);
  std::fclose(f);
  return path;
}

// Argument 1 of a benchmark below: the file read with its SHA-256, as calibrate reads it; 0: its
// bytes parsed in memory (ParseInput), the parse alone.
void ReadSession(benchmark::State& state, const std::string& path) {
  if (state.range(1) == 0) {
    const std::string bytes = ReadFileToString(path);
    std::size_t samples = 0;
    for (auto _ : state) {
      const InputData d = ParseInput(bytes, path, {});
      samples = d.raw.samples.size();
      benchmark::DoNotOptimize(d.raw.samples.data());
    }
    std::remove(path.c_str());
    state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * samples));
    return;
  }
  ReadOptions options;
  options.fingerprint = true;
  std::size_t bytes = 0, samples = 0;
  for (auto _ : state) {
    const InputData d = ReadInput(path, options);
    bytes = d.bytes;
    samples = d.raw.samples.size();
    benchmark::DoNotOptimize(d.raw.samples.data());
  }
  std::remove(path.c_str());
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * samples));
}

void BM_ReadSimulatedMcap(benchmark::State& state) {
  const McapCompression c = state.range(0) == 0   ? McapCompression::kNone
                            : state.range(0) == 1 ? McapCompression::kLz4
                                                  : McapCompression::kZstd;
  McapImuWriter writer(c);
  const std::string path = WriteSession(
      "/tmp/accelcal_bench_session.mcap",
      [&](std::uint64_t ns, const Vec3& a) { return writer.Sample(ns, a, Vec3::Zero()); },
      writer.Header(), [&] { return writer.Finish(); });
  state.SetLabel(state.range(0) == 0 ? "uncompressed" : state.range(0) == 1 ? "lz4" : "zstd");
  ReadSession(state, path);
}
BENCHMARK(BM_ReadSimulatedMcap)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// A ROS 1 bag as accelcal's writer (and rosbag) writes it: uncompressed chunks of about 768 kB,
// each followed by its index, then the connections and chunk infos (their position written into
// the header at the end: the file is rewritten there, as the CLI does).
void BM_ReadSimulatedRosBag(benchmark::State& state) {
  RosBagImuWriter writer;
  const std::string path = WriteSession(
      "/tmp/accelcal_bench_session.bag",
      [&](std::uint64_t ns, const Vec3& a) { return writer.Sample(ns, a, Vec3::Zero()); },
      writer.Header(), [&] { return writer.Finish(); });
  {
    const std::string header = writer.IndexedHeader();
    std::FILE* f = std::fopen(path.c_str(), "r+b");
    std::fseek(f, static_cast<long>(RosBagImuWriter::kHeaderOffset), SEEK_SET);
    std::fwrite(header.data(), 1, header.size(), f);
    std::fclose(f);
  }
  ReadSession(state, path);
}
BENCHMARK(BM_ReadSimulatedRosBag)
    ->ArgsProduct({{0}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Reading the file as the tool does, in blocks, with the provenance's SHA-256 on a second thread
// (argument 1) or without it (0): the difference is what the parser waits for the hash. Wall time,
// the hash being on another thread.
void BM_ReadXsens(benchmark::State& state) {
  ReadOptions options;
  options.fingerprint = state.range(0) != 0;
  std::size_t rows = 0;
  for (auto _ : state) {
    const InputData d = ReadInput(kXsens, options);
    rows = d.raw.samples.size();
    benchmark::DoNotOptimize(d.raw.samples.data());
  }
  state.SetLabel(options.fingerprint ? "with the hash" : "without the hash");
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * rows));
}
BENCHMARK(BM_ReadXsens)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DetectXsens(benchmark::State& state) {
  const InputData d = ReadInput(kXsens, {});
  for (auto _ : state) {
    const StaticDetectionResult r = DetectStaticIntervals(d.raw, {});
    benchmark::DoNotOptimize(r.intervals.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * d.raw.samples.size()));
}
BENCHMARK(BM_DetectXsens)->Unit(benchmark::kMillisecond);

void BM_Sha256Xsens(benchmark::State& state) {
  const std::string text = ReadFileToString(kXsens);
  const bool portable = state.range(0) != 0;
  state.SetLabel(portable                              ? "portable"
                 : internal::Sha256UsesShaExtensions() ? "SHA extensions"
                                                       : "portable");
  for (auto _ : state) {
    const std::string hex = portable ? internal::Sha256HexPortable(text) : Sha256Hex(text);
    benchmark::DoNotOptimize(hex.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * text.size()));
}
BENCHMARK(BM_Sha256Xsens)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// What a second thread gives on this machine at the scale of one command (BENCHMARKS.md): a
// dependent loop of range(0) steps run by the caller alone (range(1) = 0), or by the caller while a
// thread started for it runs the same loop beside it (range(1) = 1), each time after 20 ms without
// work, as a command starts. With a second core in effect both take the time of one. (Without the
// pause, iterations back to back keep the other CPU awake, and the two do run side by side.)
double Spin(std::int64_t steps) {
  double x = 1;
  for (std::int64_t i = 0; i < steps; ++i) x = x * 1.0000001 + 1e-9;
  return x;
}

void BM_SecondThread(benchmark::State& state) {
  const std::int64_t steps = state.range(0);
  const bool beside = state.range(1) != 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    state.ResumeTiming();
    double other = 0;
    std::thread thread;
    if (beside) thread = std::thread([&] { other = Spin(steps); });
    benchmark::DoNotOptimize(Spin(steps));
    if (beside) thread.join();
    benchmark::DoNotOptimize(other);
  }
  state.SetLabel(beside ? "and a thread beside it" : "alone");
}
BENCHMARK(BM_SecondThread)
    ->ArgsProduct({{500'000, 2'000'000, 20'000'000}, {0, 1}})
    ->Iterations(30)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace accelcal
