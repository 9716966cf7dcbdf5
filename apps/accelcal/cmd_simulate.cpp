// accelcal simulate: recordings of a known device.
#include "commands.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "accelcal/dataflash_writer.hpp"
#include "accelcal/mat_writer.hpp"
#include "accelcal/mcap_writer.hpp"
#include "accelcal/rosbag2_writer.hpp"
#include "accelcal/rosbag_writer.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/system_level.hpp"
#include "accelcal/ulog_writer.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {
namespace {

// Paper 001 §4.1 as a positions file: eq. (19)'s device (g units, z-first), 300 Gaussian attitudes
// from the seed, σ = 0.1 g per averaged reading, written as 100 samples of σ = 1 g so that
// calibrate takes the known noise (SigmasOfMeans) as it would from a raw log.
std::string SunXu2020Positions(const SimulateArgs& args) {
  if (args.raw) {
    throw UsageError(
        "--scenario sunxu2020 is defined on averaged readings (sigma = 0.1 g per "
        "position): use --positions-out");
  }
  if (!args.truth.empty() || !args.positions.empty() || args.noise_density_ug) {
    throw UsageError("--scenario sunxu2020 fixes the device, the attitudes and the noise");
  }
  const std::vector<Vec3> means =
      SimulateLinearPositions(SunXu2020Ta(), SunXu2020Ba(), SunXu2020Directions(300, args.seed),
                              kSunXu2020Sigma_g, args.seed + 1000);
  const double samples = 100;
  return PositionsCsv(means, samples, Vec3::Constant(kSunXu2020Sigma_g * std::sqrt(samples)));
}

}  // namespace

namespace {

// A simulated log or series beyond this many samples (28 hours at 1 kHz; several GB of text) is
// an option typed wrong, not a recording anyone wants.
constexpr double kMaxSimulatedSamples = 1e8;

void CheckSimulatedSamples(double samples, const char* options) {
  if (!(samples <= kMaxSimulatedSamples)) {
    throw UsageError(Format("%s asks for %.0f samples; at most %.0f are simulated", options,
                            samples, kMaxSimulatedSamples));
  }
}

}  // namespace

namespace {

// wu2018-system: the system-level calibration's series, streamed to -o.
void WriteSystemSeries(const SimulateArgs& args) {
  if (!args.truth.empty() || !args.positions.empty() || args.noise_density_ug || args.raw) {
    throw UsageError("--scenario wu2018-system takes only --seed, --rate, --duration and -o");
  }
  if (args.output.empty()) {
    throw UsageError("--scenario wu2018-system writes a binary series: give -o FILE");
  }
  SystemSimulationOptions o;
  o.seed = args.seed;
  if (args.rate_given) o.rate_hz = args.rate_hz;
  if (args.duration_given) o.duration_s = args.duration_s;
  if (!(o.rate_hz > 0 && o.rate_hz <= kMaxRate_hz) || !(o.duration_s > 0)) {
    throw UsageError(Format("--rate must be in (0, %g] Hz and --duration positive", kMaxRate_hz));
  }
  CheckSimulatedSamples(o.rate_hz * o.duration_s, "--rate x --duration");
  OutputFile file(args.output);  // streamed: the series is never held whole
  std::string bytes;
  AppendSeriesHeader(&bytes);
  file.Write(bytes);
  SimulateSystemLevel(o, [&](const SystemSample& s) {
    bytes.clear();
    AppendSeriesSample(s, &bytes);
    file.Write(bytes);
  });
  file.Commit();
}

// The device a simulation records (--scenario yang2012's, or --truth's), its positions and its
// noise density.
struct Device {
  ModelParameters truth;
  double gravity = 0;
  std::string positions;
  double density = 0;
};
Device DeviceOf(const SimulateArgs& args) {
  ModelParameters truth;
  double gravity = 0;
  std::string positions = args.positions;
  std::optional<double> density = args.noise_density_ug;
  if (!args.scenario.empty()) {
    if (args.scenario != "yang2012") {
      throw UsageError("--scenario: '" + args.scenario +
                       "' is not one of yang2012, sunxu2020, wu2018-system");
    }
    if (!args.truth.empty()) throw UsageError("give --scenario or --truth, not both");
    truth = Yang2012Truth();
    gravity = kYang2012Gravity_ms2;
    if (positions.empty()) positions = "yang18";
    if (!density) density = 10.0;
  } else {
    if (args.truth.empty()) throw UsageError("give --scenario or --truth");
    const LoadedCalibration cal =
        ParseCalibrationJson(ReadFileToString(args.truth, kMaxSmallFileBytes), args.truth);
    WarnVaryingNotUsed(cal, args.truth, "simulated");
    truth = cal.params;
    gravity = cal.gravity;
    if (positions.empty()) throw UsageError("--positions is required with --truth");
    if (!density) throw UsageError("--noise-density is required with --truth");
  }
  return {truth, gravity, positions, *density};
}

// ROS stamps in ns from 0 s.
std::uint64_t RosNs(double t) { return static_cast<std::uint64_t>(std::llround(t * 1e9)); }

using Sink = std::function<void(double time_s, const Vec3& raw)>;

// --format db3: a ROS 2 bag, written by SQLite into the file that will replace the output.
void WriteDb3(const SimulateArgs& args, OutputFile& file,
              const std::function<void(const Sink&)>& simulate) {
  // An SQLite journal beside the file replaced belongs to the old database, and the next
  // SQLite reader would apply it to the new one (rolled back onto it, or its pages read).
  for (const char* suffix : {"-journal", "-wal", "-shm"}) {
    struct stat st;
    if (::lstat((file.target() + suffix).c_str(), &st) == 0) {
      throw OutputError(args.output + ": " + file.target() + suffix +
                        " exists beside it: the journal of the database it would replace, "
                        "which SQLite would apply to the new bag; remove it first, or write "
                        "another file");
    }
  }
  const std::size_t slash = file.target().rfind('/');
  const std::string name = file.target().substr(slash == std::string::npos ? 0 : slash + 1);
  try {
    Rosbag2SqliteImuWriter writer(file.temporary(), "/imu/data", name);
    simulate([&](double t, const Vec3& p) { writer.Sample(RosNs(t), p); });
    writer.Finish();
  } catch (const std::runtime_error& e) {
    // SQLite's reason, for the file the user named (not the temporary one).
    std::string why = e.what();
    if (why.rfind(file.temporary() + ": ", 0) == 0) why.erase(0, file.temporary().size() + 2);
    throw OutputError(args.output + ": " + why);
  }
  file.Commit();
}

// --raw: the log in --format, streamed to -o or stdout, never held whole.
void WriteRawLog(const SimulateArgs& args, const Device& device,
                 const std::vector<Vec3>& directions, const Vec3& sigma_raw) {
  RawLogSimulation options;
  options.rate_hz = args.rate_hz;
  options.static_s = args.duration_s;
  options.transition_s = args.transition_s;
  options.sigma_raw_per_sample = sigma_raw;
  options.seed = args.seed;
  CheckSimulatedSamples(SimulatedSampleCount(directions.size(), options),
                        "positions x (--duration + --transition) x --rate");
  // A ROS time holds its seconds in 32 bits: ROS 1 unsigned (to 2106), ROS 2 signed (2038).
  const double last_s = (SimulatedSampleCount(directions.size(), options) - 1) / args.rate_hz;
  const double most_s = args.format == "rosbag" ? 4294967295.0 : 2147483647.0;
  if ((args.format == "rosbag" || args.format == "mcap" || args.format == "db3") &&
      !(last_s <= most_s)) {
    throw UsageError(
        Format("--format %s stamps its messages from 0 s in ROS time, at most %.10g "
               "s; this session lasts %.4g s",
               args.format.c_str(), most_s, last_s));
  }
  OutputFile file(args.output.empty() ? "-" : args.output);  // streamed, never held whole
  const auto simulate = [&](const Sink& sink) {
    SimulateRawLog(device.truth, device.gravity, directions, options, sink);
  };
  if (args.format == "dataflash") {
    const DataFlashImuWriter writer;
    file.Write(writer.Header());
    simulate([&](double t, const Vec3& p) {
      file.Write(writer.Sample(static_cast<std::uint64_t>(std::llround(t * 1e6)), p, Vec3::Zero()));
    });
    file.Commit();
    return;
  }
  if (args.format == "rosbag" || args.format == "db3") {
    // A bag's header is completed at its end, and SQLite writes a file by its name: both need
    // the file that will replace the output, not a stream.
    if (file.temporary().empty()) {
      throw UsageError("--format " + args.format +
                       " writes a file completed at its end: give -o FILE, a file to create "
                       "or replace (not stdout, a device or a FIFO)");
    }
  }
  if (args.format == "rosbag") {
    RosBagImuWriter writer;
    file.Write(writer.Header());
    simulate([&](double t, const Vec3& p) { file.Write(writer.Sample(RosNs(t), p)); });
    file.Write(writer.Finish());
    file.Rewrite(RosBagImuWriter::kHeaderOffset, writer.IndexedHeader());
    file.Commit();
    return;
  }
  if (args.format == "db3") {
    WriteDb3(args, file, simulate);
    return;
  }
  if (args.format == "mat") {
    // A 4 x N matrix "imu" (time [s], x, y, z per column), its sample count known first.
    MatMatrixWriter writer(
        "imu", 4, static_cast<std::uint64_t>(SimulatedSampleCount(directions.size(), options)));
    file.Write(writer.Header());
    simulate([&](double t, const Vec3& p) {
      const double column[4] = {t, p(0), p(1), p(2)};
      file.Write(writer.Column(column));
    });
    file.Write(writer.Finish());
    file.Commit();
    return;
  }
  if (args.format == "mcap") {
    McapImuWriter writer;
    file.Write(writer.Header());
    simulate([&](double t, const Vec3& p) { file.Write(writer.Sample(RosNs(t), p)); });
    file.Write(writer.Finish());
    file.Commit();
    return;
  }
  if (args.format == "ulog") {
    const ULogImuWriter writer;
    file.Write(writer.Header());
    simulate([&](double t, const Vec3& p) {
      file.Write(writer.Accel(static_cast<std::uint64_t>(std::llround(t * 1e6)), p));
    });
    file.Commit();
    return;
  }
  file.Write("time,x,y,z\n");
  simulate([&](double t, const Vec3& p) {
    file.Write(FormatNumber(t) + "," + FormatNumber(p(0)) + "," + FormatNumber(p(1)) + "," +
               FormatNumber(p(2)) + "\n");
  });
  file.Commit();
}

}  // namespace

int RunSimulate(const SimulateArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.truth, args.positions});
  if (args.format != "csv" && args.format != "ulog" && args.format != "dataflash" &&
      args.format != "mcap" && args.format != "rosbag" && args.format != "db3" &&
      args.format != "mat") {
    throw UsageError("--format is csv, ulog, dataflash, rosbag, mcap, db3 or mat, not \"" +
                     args.format + "\"");
  }
  if (args.format != "csv" && (!args.raw || args.scenario == "wu2018-system")) {
    throw UsageError("--format " + args.format +
                     " writes a raw log: give --raw (and no wu2018-system scenario)");
  }
  if (args.scenario == "wu2018-system") {
    WriteSystemSeries(args);
    return kExitOk;
  }
  if (args.scenario == "sunxu2020") {
    WriteFileAtomically(args.output.empty() ? "-" : args.output, SunXu2020Positions(args));
    return kExitOk;
  }
  const Device device = DeviceOf(args);
  if (!(device.density > 0) || !(args.rate_hz > 0) || !(args.duration_s > 0) ||
      !(args.transition_s >= 0) || !std::isfinite(device.density) ||
      !std::isfinite(args.duration_s) || !std::isfinite(args.transition_s)) {
    throw UsageError(
        "--noise-density, --rate and --duration must be positive, --transition "
        "zero or positive");
  }
  if (!(args.rate_hz <= kMaxRate_hz)) {
    throw UsageError(Format("--rate must be a number of Hz in (0, %g]", kMaxRate_hz));
  }
  // A position averages round(duration x rate) samples: at least one, and a whole number a
  // positions file can state (2^53).
  const double per_position = std::round(args.duration_s * args.rate_hz);
  if (!(per_position >= 1 && per_position <= 9007199254740992.0)) {
    throw UsageError(
        Format("--duration x --rate must be 1 to 2^53 samples per position (%g)", per_position));
  }
  const std::vector<Vec3> directions = PlannedDirections(device.positions);
  // Per-sample white noise.
  const Vec3 sigma_raw =
      RawNoiseFromDensity(device.truth, device.gravity, device.density, args.rate_hz);
  if (args.raw) {
    WriteRawLog(args, device, directions, sigma_raw);
    return kExitOk;
  }
  const std::vector<Vec3> means = SimulatePositions(device.truth, device.gravity, directions,
                                                    sigma_raw / std::sqrt(per_position), args.seed);
  WriteFileAtomically(args.output.empty() ? "-" : args.output,
                      PositionsCsv(means, per_position, sigma_raw));
  return kExitOk;
}

CommandRun SetUpSimulate(CLI::App* cmd) {
  auto a = std::make_shared<SimulateArgs>();
  cmd->add_option("--scenario", a->scenario,
                  "yang2012: paper 000's device, 18 positions, 10 ug/sqrt(Hz), 100 Hz, 60 s; "
                  "sunxu2020: paper 001's, 300 Gaussian attitudes, 0.1 g per position; "
                  "wu2018-system: paper 003's system-level series (Tables 2-3, 40 deg, "
                  "5e-3 m/s2, 100 Hz, 24 h; binary, -o required)");
  cmd->add_option("--truth", a->truth, "calibration file of the simulated device");
  cmd->add_option("--positions", a->positions,
                  "yang18, six, random:N[:SEED], or a file of unit directions or attitudes "
                  "(as for design)");
  cmd->add_option("--noise-density", a->noise_density_ug, "white noise [ug/sqrt(Hz)]");
  cmd->add_option("--rate", a->rate_hz, "sample rate [Hz]")->capture_default_str();
  cmd->add_option("--duration", a->duration_s, "still time per position [s]")
      ->capture_default_str();
  cmd->add_option("--transition", a->transition_s, "turning time between positions [s]")
      ->capture_default_str();
  cmd->add_option("--seed", a->seed, "noise seed")->capture_default_str();
  cmd->add_flag("--raw", a->raw, "write a raw log (time,x,y,z) instead of positions");
  cmd->add_flag("!--positions-out", a->raw,
                "write a positions file x,y,z,n,sx,sy,sz (the default)");
  cmd->add_option("--format", a->format,
                  "of a raw log: csv (time,x,y,z), ulog (PX4's sensor_accel), dataflash "
                  "(ArduPilot's IMU records), both float32; rosbag (ROS 1 bag, "
                  "sensor_msgs/Imu), mcap (ROS 2, zstd chunks) or db3 (ROS 2 SQLite), each "
                  "/imu/data stamped from 0 s; or mat (MATLAB v5: a 4 x N matrix imu of "
                  "time, x, y, z per column)")
      ->capture_default_str();
  cmd->add_option("-o,--output", a->output, "output file (default: stdout)")->check(kFileName);
  return [a](const CLI::App& parsed) {
    a->rate_given = parsed.count("--rate") > 0;
    a->duration_given = parsed.count("--duration") > 0;
    return RunSimulate(*a);
  };
}

}  // namespace accelcal::cli
