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

// A ROS 1 bag: its records (4-byte lengths, "name=value" header fields), one connection, chunks of
// about 768 kB uncompressed, no index (a reader in record order needs none).
template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof(T));
}
std::string Field(const std::string& name, const std::string& value) {
  std::string f;
  Put<std::uint32_t>(&f, static_cast<std::uint32_t>(name.size() + 1 + value.size()));
  return f + name + "=" + value;
}
std::string Record(const std::string& header, const std::string& data) {
  std::string r;
  Put<std::uint32_t>(&r, static_cast<std::uint32_t>(header.size()));
  r += header;
  Put<std::uint32_t>(&r, static_cast<std::uint32_t>(data.size()));
  return r + data;
}
std::string Le32(std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }

void BM_ReadSimulatedRosBag(benchmark::State& state) {
  const std::string definition =
      "Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
      "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
      "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"
      "===\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"
      "===\nMSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n"
      "===\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
  const std::string connection =
      Record(Field("op", "\x07") + Field("conn", Le32(0)) + Field("topic", "/imu/data"),
             Field("topic", "/imu/data") + Field("type", "sensor_msgs/Imu") +
                 Field("md5sum", "6a62c6daae103f4ff57a132d6f95cec2") +
                 Field("message_definition", definition));
  std::string chunk;
  std::uint32_t seq = 0;
  const auto flush = [&] {
    if (chunk.empty()) return std::string();
    const std::string r = Record(Field("op", "\x05") + Field("compression", "none") +
                                     Field("size", Le32(static_cast<std::uint32_t>(chunk.size()))),
                                 chunk);
    chunk.clear();
    return r;
  };
  const std::string path = WriteSession(
      "/tmp/accelcal_bench_session.bag",
      [&](std::uint64_t ns, const Vec3& a) {
        std::string m;
        Put<std::uint32_t>(&m, seq++);
        Put<std::uint32_t>(&m, static_cast<std::uint32_t>(ns / 1000000000u));
        Put<std::uint32_t>(&m, static_cast<std::uint32_t>(ns % 1000000000u));
        Put<std::uint32_t>(&m, 3);
        m += "imu";
        for (int i = 0; i < 4 + 9 + 3 + 9; ++i) Put<double>(&m, 0.0);
        for (int i = 0; i < 3; ++i) Put<double>(&m, a(i));
        for (int i = 0; i < 9; ++i) Put<double>(&m, 0.0);
        std::string time;
        Put<std::uint32_t>(&time, static_cast<std::uint32_t>(ns / 1000000000u));
        Put<std::uint32_t>(&time, static_cast<std::uint32_t>(ns % 1000000000u));
        chunk += Record(Field("op", "\x02") + Field("conn", Le32(0)) + Field("time", time), m);
        return chunk.size() >= 768 * 1024 ? flush() : std::string();
      },
      "#ROSBAG V2.0\n" +
          Record(Field("op", "\x03") + Field("index_pos", std::string(8, '\0')) +
                     Field("conn_count", Le32(1)) + Field("chunk_count", Le32(0)),
                 std::string(4000, ' ')) +
          Record(Field("op", "\x05") + Field("compression", "none") +
                     Field("size", Le32(static_cast<std::uint32_t>(connection.size()))),
                 connection),
      flush);
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
