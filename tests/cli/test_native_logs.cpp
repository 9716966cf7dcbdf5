// Binary logs through the command line (issue 20): a simulated session written as a PX4 ULog
// calibrates to the same bytes as its samples written as CSV; the stream is chosen or the choice
// refused with the candidates named; a log cut short is used with a warning.
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include "accelcal/dataflash_writer.hpp"
#include "accelcal/mcap_writer.hpp"
#include "accelcal/rosbag2_writer.hpp"
#include "accelcal/rosbag_writer.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/ulog_writer.hpp"
#include "io/binary_stream.hpp"
#include "io/dataflash.hpp"
#include "io/input_file.hpp"
#include "io/ulog.hpp"
#include "support/cli_test.hpp"
#include "support/paths.hpp"

namespace accelcal::test {
namespace {

class NativeLogTest : public CliTest {};

const std::string kSmall = std::string(ACCELCAL_DATA_DIR) + "/px4-ulog/sample_log_small.ulg";

// A short session in m/s² as PX4's sensor_accel has it (scales near 1, an offset): 18 positions
// of 2 s, the truth and options the ULog tests below simulate.
struct MetricSession {
  ModelParameters truth;
  RawLogSimulation sim;
  MetricSession() {
    truth.K = Vec3(1.002, 0.998, 1.001).asDiagonal();
    truth.bias = Vec3(0.05, -0.03, 0.08);
    sim.static_s = 2.0;
    sim.transition_s = 1.0;
    sim.sigma_raw_per_sample = Vec3::Constant(1e-3);  // some noise: detection needs it
  }
  // The session as a ULog of sensor_accel, each message as `edit` leaves it.
  std::string ULog(const std::function<void(std::string*)>& edit = {}) const {
    const ULogImuWriter writer;
    std::string ulog = writer.Header();
    SimulateRawLog(truth, 9.81, Yang18Directions(), sim, [&](double t, const Vec3& a) {
      std::string message = writer.Accel(static_cast<std::uint64_t>(std::llround(t * 1e6)), a);
      if (edit) edit(&message);
      ulog += message;
    });
    return ulog;
  }
};

// The ULog's sensor_accel samples as CSV: the times in µs as the integers they are, the float32
// readings as the doubles they are (17 digits read back exactly).
std::string AsCsv(const std::string& ulog) {
  internal::InputFile file(ulog, std::size_t{1} << 30);
  internal::BinaryStream in(&file, "");
  const internal::DecodedLog c = internal::ReadULog(
      in, [](const internal::DecodedStream& s) { return s.topic == "sensor_accel"; });
  const internal::DecodedStream& s = c.streams.at(0);
  const auto col = [&](const char* name) {
    return std::size_t(std::find(s.columns->begin(), s.columns->end(), name) - s.columns->begin());
  };
  const std::size_t t = col("timestamp_sample"), x = col("x"), y = col("y"), z = col("z");
  std::string out = "timestamp_sample,x,y,z\n";
  char line[160];
  for (std::size_t i = 0; i < s.messages; ++i) {
    const double* row = s.values.data() + i * s.columns->size();
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g\n",
                  static_cast<unsigned long long>(row[t]), row[x], row[y], row[z]);
    out += line;
  }
  return out;
}

// The calibration file less the input's name and its provenance (name, size and digest).
nlohmann::json Calibration(const std::string& path) {
  nlohmann::json j = nlohmann::json::parse(Slurp(path));
  j.erase("provenance");
  j["sensors"]["accelerometer"].erase("source");
  return j;
}

TEST_F(NativeLogTest, ULogCalibratesToTheSameBytesAsItsSamplesAsCsv) {
  ASSERT_EQ(
      Exec("simulate --scenario yang2012 --raw --format ulog --duration 20 -o " + Path("s.ulg"))
          .status,
      0);
  const std::string csv = Write("s.csv", AsCsv(Path("s.ulg")));
  const CliRun u = Exec("calibrate " + Path("s.ulg") + " -o " + Path("u.json"));
  // sensor_accel is in m/s2 by PX4's definition, which the calibration's raw unit says.
  const CliRun c =
      Exec("calibrate " + csv + " --time-unit us --raw-units m/s2 -o " + Path("c.json"));
  ASSERT_EQ(u.status, 0) << u.err;
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_EQ(Calibration(Path("u.json")).dump(1), Calibration(Path("c.json")).dump(1));
  // The samples are PX4's float32: the ULog's own timestamps were read, in µs.
  EXPECT_NE(u.out.find("time in us"), std::string::npos) << u.out;
}

// A PX4 driver that leaves timestamp_sample 0 (issue 47): the refusal names the field and the
// time the logger stamped each message (timestamp), which then reads the session as it is.
TEST_F(NativeLogTest, ULogWithoutSampleTimesSuggestsItsTimestamp) {
  Write("z.ulg", MetricSession().ULog([](std::string* message) {
    // size (2), type (1), msg_id (2), timestamp (8), then timestamp_sample (8): zeroed.
    std::fill(message->begin() + 13, message->begin() + 21, '\0');
  }));
  CliRun e = Exec("calibrate " + Path("z.ulg") + " --gravity 9.81 -q -o " + Path("z.json"));
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("sensor_accel's timestamp_sample is the same in every message (0 us): the "
                       "sensor's driver does not stamp them; read the time the recorder logged "
                       "each with --columns (timestamp,x,y,z)"),
            std::string::npos)
      << e.err;
  e = Exec("calibrate " + Path("z.ulg") + " --gravity 9.81 --columns timestamp,x,y,z -q -o " +
           Path("z.json"));
  EXPECT_EQ(e.status, 0) << e.err;
}

// The gyroscope too: an IMU session (accelerometer and gyroscope, Xsens-like counts, noise) as a
// ULog with sensor_accel and sensor_gyro, and as two CSVs of the same float32 samples; the joint
// calibration from the one and from the others is the same, byte for byte.
// A simulated session as ArduPilot logs it (IMU records) calibrates as its samples as CSV.
TEST_F(NativeLogTest, DataFlashCalibratesToTheSameBytesAsItsSamplesAsCsv) {
  ASSERT_EQ(Exec("simulate --scenario yang2012 --raw --format dataflash --duration 20 -o " +
                 Path("s.bin"))
                .status,
            0);
  internal::InputFile file(Path("s.bin"), std::size_t{1} << 30);
  internal::BinaryStream in(&file, "");
  const internal::DecodedLog c = internal::ReadDataFlash(
      in, [](const internal::DecodedStream& s) { return s.topic == "IMU"; });
  const internal::DecodedStream& s = c.streams.at(0);
  std::string csv = "time_us,x,y,z\n";
  char line[160];
  for (std::size_t i = 0; i < s.messages; ++i) {
    const double* row = s.values.data() + i * s.columns->size();  // TimeUS, I, Gyr, Acc, ...
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g\n",
                  static_cast<unsigned long long>(row[0]), row[5], row[6], row[7]);
    csv += line;
  }
  Write("s.csv", csv);
  const CliRun d = Exec("calibrate " + Path("s.bin") + " -o " + Path("d.json"));
  const CliRun t =
      Exec("calibrate " + Path("s.csv") + " --time-unit us --raw-units m/s2 -o " + Path("t.json"));
  ASSERT_EQ(d.status, 0) << d.err;
  ASSERT_EQ(t.status, 0) << t.err;
  EXPECT_EQ(Calibration(Path("d.json")).dump(1), Calibration(Path("t.json")).dump(1));
  // ArduPilot's IMU records are corrected by the calibration in force, which the summary says.
  EXPECT_NE(d.out.find("already corrected by the calibration in force"), std::string::npos)
      << d.out;
}

TEST_F(NativeLogTest, ImuULogCalibratesTheGyroscopeToTheSameBytesAsCsv) {
  RawLogSimulation options;
  options.static_s = 4.0;
  options.transition_s = 2.0;
  options.sigma_raw_per_sample = Vec3(2, 2, 2);
  GyroSimulation gyro;
  gyro.truth.K << 4778, 12, -8, -15, 4758, 20, 9, -11, 4766;  // counts per rad/s
  gyro.truth.bias = Vec3(32740, 32810, 32650);
  gyro.sigma_raw_per_sample = Vec3(3, 3, 3);
  ModelParameters accel = Yang2012Truth();
  accel.bias += Vec3(32768, 32768, 32768);  // counts, as the Xsens
  const SimulatedImuLog log = SimulateImuLog(accel, 9.81, Yang18Directions(), options, gyro);
  const ULogImuWriter writer(7, true);
  std::string ulog = writer.Header(), acc = "time_us,x,y,z\n", rates = acc;
  char line[160];
  const auto row = [&](std::string* csv, std::uint64_t t, const Vec3& v) {
    const auto f = [](double x) { return static_cast<double>(static_cast<float>(x)); };
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g\n", static_cast<unsigned long long>(t),
                  f(v(0)), f(v(1)), f(v(2)));
    *csv += line;
  };
  for (std::size_t k = 0; k < log.time_s.size(); ++k) {
    const auto t = static_cast<std::uint64_t>(std::llround(log.time_s[k] * 1e6));
    ulog += writer.Accel(t, log.accel[k]);
    ulog += writer.Gyro(t, log.gyro[k]);
    row(&acc, t, log.accel[k]);
    row(&rates, t, log.gyro[k]);
  }
  const std::string u = Write("imu.ulg", ulog), a = Write("acc.csv", acc),
                    g = Write("gyro.csv", rates);
  const CliRun from_ulog =
      Exec("calibrate " + u + " --gravity 9.81 --gyro " + u + " -o " + Path("u.json"));
  const CliRun from_csv =
      Exec("calibrate " + a + " --gravity 9.81 --time-unit us --raw-units m/s2 --gyro " + g +
           " -o " + Path("c.json"));
  ASSERT_EQ(from_ulog.status, 0) << from_ulog.err;
  ASSERT_EQ(from_csv.status, 0) << from_csv.err;
  nlohmann::json ju = Calibration(Path("u.json")), jc = Calibration(Path("c.json"));
  ASSERT_TRUE(ju["sensors"].contains("gyroscope"));
  // The raw unit labelled by sensor_gyro's definition (the CSV's rates are unlabelled "raw").
  EXPECT_EQ(ju["sensors"]["gyroscope"]["units"]["raw"], "rad/s");
  EXPECT_EQ(jc["sensors"]["gyroscope"]["units"]["raw"], "raw");
  for (nlohmann::json* j : {&ju, &jc}) {
    (*j)["sensors"]["gyroscope"].erase("source");
    (*j)["sensors"]["gyroscope"]["units"].erase("raw");
  }
  EXPECT_EQ(ju.dump(1), jc.dump(1));
  // The gyroscope's stream by name, and a topic that holds none.
  EXPECT_EQ(Exec("calibrate " + u + " --gravity 9.81 --gyro " + u +
                 " --gyro-topic sensor_gyro -q -o " + Path("t.json"))
                .status,
            0);
  const CliRun wrong = Exec("calibrate " + u + " --gravity 9.81 --gyro " + u +
                            " --gyro-topic sensor_mag -o " + Path("w.json"));
  EXPECT_NE(wrong.err.find("no stream of topic sensor_mag with samples (its topics: "
                           "sensor_accel, sensor_gyro)"),
            std::string::npos)
      << wrong.err;
  const CliRun alone = Exec("calibrate " + u + " --gyro-topic sensor_gyro");
  EXPECT_NE(alone.err.find("--gyro-topic applies to the gyroscope"), std::string::npos)
      << alone.err;
}

// ROS 2: an IMU session (accelerometer and gyroscope) as an MCAP file of sensor_msgs/msg/Imu, its
// chunks uncompressed, lz4 and zstd, and as two CSVs of the same float64 samples: the joint
// calibration from each MCAP file is the one from the CSVs, byte for byte.
TEST_F(NativeLogTest, McapCalibratesToTheSameBytesAsItsSamplesAsCsv) {
  RawLogSimulation options;
  options.static_s = 4.0;
  options.transition_s = 2.0;
  options.sigma_raw_per_sample = Vec3(2, 2, 2);
  GyroSimulation gyro;
  gyro.truth.K << 4778, 12, -8, -15, 4758, 20, 9, -11, 4766;
  gyro.truth.bias = Vec3(32740, 32810, 32650);
  gyro.sigma_raw_per_sample = Vec3(3, 3, 3);
  ModelParameters accel = Yang2012Truth();
  accel.bias += Vec3(32768, 32768, 32768);
  const SimulatedImuLog log = SimulateImuLog(accel, 9.81, Yang18Directions(), options, gyro);
  std::string acc = "time_us,x,y,z\n", rates = acc;
  char line[160];
  const auto row = [&](std::string* csv, std::uint64_t t_us, const Vec3& v) {
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g\n",
                  static_cast<unsigned long long>(t_us), v(0), v(1), v(2));
    *csv += line;
  };
  // Stamped from 1.7e9 s, as a live recording; in whole µs, which the CSVs hold exactly.
  const std::uint64_t t0_us = 1700000000000000u;
  for (std::size_t k = 0; k < log.time_s.size(); ++k) {
    const auto t = t0_us + static_cast<std::uint64_t>(std::llround(log.time_s[k] * 1e6));
    row(&acc, t, log.accel[k]);
    row(&rates, t, log.gyro[k]);
  }
  const std::string a = Write("acc.csv", acc), g = Write("gyro.csv", rates);
  const CliRun from_csv =
      Exec("calibrate " + a + " --gravity 9.81 --time-unit us --raw-units m/s2 --gyro " + g +
           " -o " + Path("c.json"));
  ASSERT_EQ(from_csv.status, 0) << from_csv.err;
  nlohmann::json jc = Calibration(Path("c.json"));
  jc["sensors"]["gyroscope"].erase("source");
  jc["sensors"]["gyroscope"]["units"].erase("raw");  // a ROS Imu's rates are labelled rad/s
  for (const McapCompression compression :
       {McapCompression::kNone, McapCompression::kLz4, McapCompression::kZstd}) {
    McapImuWriter writer(compression);
    std::string mcap = writer.Header();
    for (std::size_t k = 0; k < log.time_s.size(); ++k) {
      const auto t = t0_us + static_cast<std::uint64_t>(std::llround(log.time_s[k] * 1e6));
      mcap += writer.Sample(t * 1000, log.accel[k], log.gyro[k]);
    }
    mcap += writer.Finish();
    const std::string m = Write("imu.mcap", mcap);
    const CliRun from_mcap =
        Exec("calibrate " + m + " --gravity 9.81 --gyro " + m + " -o " + Path("m.json"));
    ASSERT_EQ(from_mcap.status, 0) << from_mcap.err;
    nlohmann::json jm = Calibration(Path("m.json"));
    ASSERT_TRUE(jm["sensors"].contains("gyroscope"));
    jm["sensors"]["gyroscope"].erase("source");
    EXPECT_EQ(jm["sensors"]["gyroscope"]["units"]["raw"], "rad/s");
    jm["sensors"]["gyroscope"]["units"].erase("raw");
    EXPECT_EQ(jm.dump(1), jc.dump(1)) << static_cast<int>(compression);
    EXPECT_NE(from_mcap.out.find("an MCAP file: /imu/data"), std::string::npos) << from_mcap.out;
  }
  // The same session as a ROS 1 bag (each chunk compression) and a ROS 2 SQLite bag.
  const auto same = [&](const std::string& bag, const std::string& what) {
    const CliRun run =
        Exec("calibrate " + bag + " --gravity 9.81 --gyro " + bag + " -o " + Path("b.json"));
    ASSERT_EQ(run.status, 0) << what << run.err;
    nlohmann::json jb = Calibration(Path("b.json"));
    ASSERT_TRUE(jb["sensors"].contains("gyroscope")) << what;
    jb["sensors"]["gyroscope"].erase("source");
    EXPECT_EQ(jb["sensors"]["gyroscope"]["units"]["raw"], "rad/s") << what;
    jb["sensors"]["gyroscope"]["units"].erase("raw");
    EXPECT_EQ(jb.dump(1), jc.dump(1)) << what;
  };
  for (const RosBagCompression compression :
       {RosBagCompression::kNone, RosBagCompression::kBz2, RosBagCompression::kLz4}) {
    RosBagImuWriter writer(compression);
    std::string bag = writer.Header();
    for (std::size_t k = 0; k < log.time_s.size(); ++k) {
      const auto t = t0_us + static_cast<std::uint64_t>(std::llround(log.time_s[k] * 1e6));
      bag += writer.Sample(t * 1000, log.accel[k], log.gyro[k]);
    }
    bag += writer.Finish();
    const std::string indexed = writer.IndexedHeader();
    ASSERT_EQ(indexed.size() + RosBagImuWriter::kHeaderOffset, writer.Header().size());
    bag.replace(RosBagImuWriter::kHeaderOffset, indexed.size(), indexed);
    same(Write("imu.bag", bag), "ROS bag " + std::to_string(static_cast<int>(compression)));
  }
  {
    std::remove(Path("imu.db3").c_str());
    Rosbag2SqliteImuWriter writer(Path("imu.db3"));
    for (std::size_t k = 0; k < log.time_s.size(); ++k) {
      const auto t = t0_us + static_cast<std::uint64_t>(std::llround(log.time_s[k] * 1e6));
      writer.Sample(t * 1000, log.accel[k], log.gyro[k]);
    }
    writer.Finish();
    same(Path("imu.db3"), "db3");
  }
}

// `simulate --format` writes a session in every format, each calibrating as its samples as text:
// the MAT-file's 4 x N matrix as the CSV's rows without their header line (the same doubles; the
// time column found the same way), the bags as the samples with their ns stamps in us.
TEST_F(NativeLogTest, EverySimulatedFormatCalibratesAsItsSamples) {
  const std::string sim = "simulate --scenario yang2012 --raw --duration 10 --format ";
  ASSERT_EQ(Exec(sim + "csv -o " + Path("s.csv")).status, 0);
  const std::string csv = Slurp(Path("s.csv"));
  const std::string rows = Write("rows.txt", csv.substr(csv.find('\n') + 1));
  ASSERT_EQ(Exec(sim + "mat -o " + Path("s.mat")).status, 0);
  const CliRun text = Exec("calibrate " + rows + " -o " + Path("t.json"));
  const CliRun mat = Exec("calibrate " + Path("s.mat") + " -o " + Path("m.json"));
  ASSERT_EQ(text.status, 0) << text.err;
  ASSERT_EQ(mat.status, 0) << mat.err;
  EXPECT_EQ(Calibration(Path("m.json")).dump(1), Calibration(Path("t.json")).dump(1));
  // The bags: times in whole ns from 0 s, which as us are the CSV's times to 1e-3 us.
  std::string us = "time_us,x,y,z\n";
  {
    std::istringstream in(csv.substr(csv.find('\n') + 1));
    std::string line;
    while (std::getline(in, line)) {
      const std::size_t comma = line.find(',');
      const double t_s = std::stod(line.substr(0, comma));
      char t_us[40];
      std::snprintf(t_us, sizeof t_us, "%.17g", static_cast<double>(std::llround(t_s * 1e9)) / 1e3);
      us += t_us + line.substr(comma) + "\n";
    }
  }
  const CliRun from_us = Exec("calibrate " + Write("us.csv", us) +
                              " --time-unit us --raw-units m/s2 -o " + Path("u.json"));
  ASSERT_EQ(from_us.status, 0) << from_us.err;
  for (const char* format : {"rosbag", "db3", "mcap"}) {
    const std::string bag = Path(std::string("s.") + format);
    ASSERT_EQ(Exec(sim + format + " -o " + bag).status, 0) << format;
    const CliRun run = Exec("calibrate " + bag + " -o " + Path("b.json"));
    ASSERT_EQ(run.status, 0) << format << run.err;
    EXPECT_EQ(Calibration(Path("b.json")).dump(1), Calibration(Path("u.json")).dump(1)) << format;
    // inspect gives the file's size (a database is read by SQLite, not as a stream).
    const std::string first = Slurp(bag);
    const CliRun inspect = Exec("inspect --json " + bag);
    ASSERT_EQ(inspect.status, 0) << format << inspect.err;
    EXPECT_EQ(nlohmann::json::parse(inspect.out)["bytes"], first.size()) << format;
    // The same simulation writes the same bytes.
    ASSERT_EQ(Exec(sim + format + " -o " + bag).status, 0) << format;
    EXPECT_EQ(Slurp(bag), first) << format;
  }
  // A bag completed at its end, or a database, is not written to stdout.
  const CliRun piped = Exec(sim + "rosbag");
  EXPECT_EQ(piped.status, 2);
  EXPECT_NE(piped.err.find("give -o FILE"), std::string::npos) << piped.err;
  // The simulator's bags hold no rates, and say so (REP 145): no gyroscope read from them.
  const CliRun gyro = Exec("calibrate " + Path("s.rosbag") + " --gyro " + Path("s.rosbag"));
  EXPECT_EQ(gyro.status, 3);
  EXPECT_NE(gyro.err.find("/imu/data's angular_velocity_covariance[0] is -1 in every message, "
                          "which marks (REP 145) its angular_velocity as not measured"),
            std::string::npos)
      << gyro.err;
  // A session longer than ROS time holds: refused before anything is written.
  const CliRun late = Exec(
      "simulate --scenario yang2012 --raw --positions six --rate 1e-6 "
      "--duration 1e9 --format db3 -o " +
      Path("late.db3"));
  EXPECT_EQ(late.status, 2);
  EXPECT_NE(late.err.find("stamps its messages from 0 s in ROS time, at most 2147483647 s"),
            std::string::npos)
      << late.err;
  // An SQLite journal beside the bag replaced would be applied to the new one: refused.
  Write("s.db3-wal", "stale");
  const std::string before = Slurp(Path("s.db3"));
  const CliRun stale = Exec(sim + "db3 -o " + Path("s.db3"));
  EXPECT_EQ(stale.status, 5);
  EXPECT_NE(stale.err.find("s.db3-wal exists beside it"), std::string::npos) << stale.err;
  EXPECT_EQ(Slurp(Path("s.db3")), before);
}

// ArduPilot logs its IMU records corrected by the calibration in force: a = (p - o_old) .* s_old,
// p the sensor's reading. A session simulated through a known sensor (f = (p - o) .* s, diagonal
// as ArduPilot models it) and a known, wrong calibration in force (its PARM records, or a .param
// file): the export composes the two, and gives the sensor's own o and s back.
TEST_F(NativeLogTest, ArduPilotExportComposesWithTheCalibrationInForce) {
  const Vec3 o_true(0.35, -0.21, 0.48), s_true(1.012, 0.991, 1.004);  // m/s², unitless
  const Vec3 o_old(0.10, 0.05, -0.30), s_old(0.995, 1.006, 0.998);
  // What accelcal sees: a = f .* (s_old ./ s_true) + (o_true - o_old) .* s_old.
  ModelParameters seen;
  seen.K = s_old.cwiseQuotient(s_true).asDiagonal();
  seen.bias = (o_true - o_old).cwiseProduct(s_old);
  RawLogSimulation options;
  options.static_s = 4.0;
  options.transition_s = 2.0;
  options.sigma_raw_per_sample = Vec3(1e-3, 1e-3, 1e-3);  // m/s² per sample
  const double g = 9.80665;
  const DataFlashImuWriter writer;
  const char axes[3] = {'X', 'Y', 'Z'};
  std::string with_parm = writer.Header(), without = writer.Header();
  for (int i = 0; i < 3; ++i) {
    with_parm +=
        writer.Parameter(0, std::string("INS_ACCOFFS_") + axes[i], static_cast<float>(o_old(i)));
    with_parm +=
        writer.Parameter(0, std::string("INS_ACCSCAL_") + axes[i], static_cast<float>(s_old(i)));
  }
  SimulateRawLog(seen, g, Yang18Directions(), options, [&](double t, const Vec3& a) {
    const std::string r =
        writer.Sample(static_cast<std::uint64_t>(std::llround(t * 1e6)), a, Vec3::Zero());
    with_parm += r;
    without += r;
  });
  std::string param_file = "# the calibration in force, as Mission Planner saves it\n";
  for (int i = 0; i < 3; ++i) {
    param_file += std::string("INS_ACCOFFS_") + axes[i] + "," + std::to_string(o_old(i)) + "\n";
    param_file += std::string("INS_ACCSCAL_") + axes[i] + "," + std::to_string(s_old(i)) + "\n";
  }
  Write("old.param", param_file);
  Write("parm.bin", with_parm);
  Write("bare.bin", without);
  ASSERT_EQ(
      Exec("calibrate " + Path("parm.bin") + " --gravity 9.80665 -q -o " + Path("p.json")).status,
      0);
  ASSERT_EQ(
      Exec("calibrate " + Path("bare.bin") + " --gravity 9.80665 -q -o " + Path("b.json")).status,
      0);
  // The export's INS_ACCOFFS and INS_ACCSCAL.
  const auto exported = [&](const CliRun& run) {
    std::map<std::string, double> out;
    std::istringstream lines(Slurp(Path("e.param")));
    for (std::string line; std::getline(lines, line);) {
      if (line.empty() || line[0] == '#') continue;
      out[line.substr(0, line.find(','))] = std::stod(line.substr(line.find(',') + 1));
    }
    EXPECT_EQ(run.status, 0) << run.err;
    return out;
  };
  // The composition is exact; what is left is the estimate's noise (σ ≈ 3e-5 m/s² on an offset,
  // 3e-6 on a scale, from 1e-3 m/s² per sample over 18 positions of 400 samples) and the records'
  // float32 rounding (6e-8 relative): 5e-4 and 5e-5 are more than ten σ, and the uncomposed
  // values are off by 0.25-0.78 m/s² and 0.7-1.7 %.
  for (const std::string& how :
       {std::string("p.json"), std::string("b.json --current-params ") + Path("old.param")}) {
    const std::map<std::string, double> p =
        exported(Exec("export " + Path(how) + " --to ardupilot -o " + Path("e.param")));
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(p.at(std::string("INS_ACCOFFS_") + axes[i]), o_true(i), 5e-4) << how;
      EXPECT_NEAR(p.at(std::string("INS_ACCSCAL_") + axes[i]), s_true(i), 5e-5) << how;
    }
    EXPECT_NE(Slurp(Path("e.param")).find("# composed with the calibration in force"),
              std::string::npos);
  }
  // Without the calibration in force, no export: it would be wrong for the sensor.
  const CliRun missing = Exec("export " + Path("b.json") + " --to ardupilot");
  EXPECT_EQ(missing.status, 3);
  EXPECT_NE(missing.err.find("do not hold INS_ACCOFFS_X: give the parameters in force when the log "
                             "was recorded (--current-params FILE.param)"),
            std::string::npos)
      << missing.err;
  // A board rotated by AHRS_ORIENTATION: the records are rotated after the correction.
  Write("rotated.param", param_file + "AHRS_ORIENTATION,2\n");
  const CliRun rotated = Exec("export " + Path("b.json") + " --to ardupilot --current-params " +
                              Path("rotated.param"));
  EXPECT_NE(rotated.err.find("AHRS_ORIENTATION is 2"), std::string::npos) << rotated.err;
  // --current-params is ArduPilot's.
  EXPECT_EQ(
      Exec("export " + Path("b.json") + " --to px4 --current-params " + Path("old.param")).status,
      2);
}

// PX4 matches a calibration to its sensor by device id: the export writes CAL_ACC<n>_ID from the
// ULog's sensor_accel (or --device-id) and PX4's default priority, and refuses a calibration of
// sensor_combined, which the calibration in force had corrected.
TEST_F(NativeLogTest, Px4ExportNamesTheSensorByItsDeviceId) {
  ASSERT_EQ(
      Exec("simulate --scenario yang2012 --raw --format ulog --duration 20 -o " + Path("s.ulg"))
          .status,
      0);
  ASSERT_EQ(Exec("calibrate " + Path("s.ulg") + " -q -o " + Path("u.json")).status, 0);
  const nlohmann::json cal = nlohmann::json::parse(Slurp(Path("u.json")));
  const nlohmann::json& stream = cal["provenance"]["inputs"][0]["stream"];
  EXPECT_EQ(stream["format"], "ulog");
  EXPECT_EQ(stream["topic"], "sensor_accel");
  EXPECT_EQ(stream["device_id"], 1);  // ULogImuWriter's default
  EXPECT_EQ(stream["corrected"], false);
  // The simulated counts are not m/s²: --raw-unit m/s2 vouching for them does not make scales of
  // 0.0002 plausible (issue 47: it wrote CAL_ACC0_XSCALE 0.000208).
  CliRun e = Exec("export " + Path("u.json") + " --to px4 --raw-unit m/s2");
  EXPECT_EQ(e.status, 3);
  EXPECT_EQ(e.out, "");
  EXPECT_NE(e.err.find("PX4 would apply scales of 0.000"), std::string::npos) << e.err;
  EXPECT_NE(e.err.find("the raw unit given (--raw-unit m/s2) does not fit these readings"),
            std::string::npos)
      << e.err;
  EXPECT_EQ(Exec("export " + Path("u.json") + " --to ardupilot --raw-unit m/s2").status, 3);
  // A session in m/s² (its scales near 1).
  Write("m.ulg", MetricSession().ULog());
  ASSERT_EQ(Exec("calibrate " + Path("m.ulg") + " --gravity 9.81 -q -o " + Path("m.json")).status,
            0);
  e = Exec("export " + Path("m.json") + " --to px4 --raw-unit m/s2");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("1\t1\tCAL_ACC0_ID\t1\t6\n1\t1\tCAL_ACC0_PRIO\t50\t6\n"), std::string::npos)
      << e.out;
  EXPECT_NE(e.out.find("# CAL_ACC0: sensor_accel instance 0 of the log, device id 1; slot 0: the "
                       "log holds no CAL_ACCn_ID: CAL_ACC0 is the first slot it leaves free"),
            std::string::npos)
      << e.out;
  e = Exec("export " + Path("m.json") +
           " --to px4 --raw-unit m/s2 --device-id 3670050 "
           "--instance 2");
  EXPECT_NE(e.out.find("1\t1\tCAL_ACC2_ID\t3670050\t6\n"), std::string::npos) << e.out;
  // A calibration of sensor_combined (its record edited so): refused, with what to do.
  nlohmann::json combined = cal;
  combined["provenance"]["inputs"][0]["stream"]["topic"] = "sensor_combined";
  combined["provenance"]["inputs"][0]["stream"]["corrected"] = true;
  Write("c.json", combined.dump());
  e = Exec("export " + Path("c.json") + " --to px4 --raw-unit m/s2");
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("calibrate sensor_accel"), std::string::npos) << e.err;
  // --device-id is PX4's.
  EXPECT_EQ(Exec("export " + Path("u.json") + " --to ardupilot --device-id 5").status, 2);
  // The simulated counts under the stream's label m/s2 (no --raw-unit to vouch for them): scales
  // of 0.0002 are no sensor's, and PX4 would apply them as written.
  e = Exec("export " + Path("u.json") + " --to px4");
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("PX4 would apply scales of 0.000"), std::string::npos) << e.err;
  EXPECT_NE(e.err.find("these readings were not in 'm/s2' (counts?)"), std::string::npos) << e.err;
  // PX4's slots are 0 to 3; a device id is 1 to 2^32 - 1; a gyroscope's needs a gyroscope.
  const std::string px4 = "export " + Path("m.json") + " --to px4 --raw-unit m/s2 ";
  e = Exec(px4 + "--instance 4");
  EXPECT_EQ(e.status, 2);
  EXPECT_NE(e.err.find("PX4 has calibration slots 0 to 3"), std::string::npos) << e.err;
  for (const char* id : {"0", "-1", "4294967296", "1e3"}) {
    e = Exec(px4 + "--device-id " + id);
    EXPECT_EQ(e.status, 2) << id;
    EXPECT_NE(e.err.find("a device id is an integer from 1 to 4294967295"), std::string::npos)
        << e.err;
  }
  e = Exec(px4 + "--gyro-device-id 5");
  EXPECT_EQ(e.status, 2);
  EXPECT_NE(e.err.find("a calibration without a gyroscope"), std::string::npos) << e.err;
}

// PX4 applies CAL_ACC<n> to the sensor whose device id is CAL_ACC<n>_ID: the export takes the
// slot the log's parameters give the stream's device id (issue 47: it wrote CAL_ACC0 for device
// 1 of slot CAL_ACC1, replacing the primary IMU's calibration), refuses an --instance that
// contradicts it, and without a match takes the first free slot and says so.
TEST_F(NativeLogTest, Px4ExportTakesTheSlotTheLogGivesTheSensor) {
  const MetricSession m;
  GyroSimulation gyro;  // rad/s, as PX4's sensor_gyro, with an offset
  gyro.truth.bias = Vec3(0.01, -0.02, 0.005);
  gyro.sigma_raw_per_sample = Vec3::Constant(1e-3);
  const SimulatedImuLog imu = SimulateImuLog(m.truth, 9.81, Yang18Directions(), m.sim, gyro);
  const ULogImuWriter writer(1, true, 9);  // accelerometer device 1, gyroscope device 9
  const auto session = [&](const std::string& parameters) {
    std::string ulog = writer.Header(parameters);
    for (std::size_t k = 0; k < imu.time_s.size(); ++k) {
      const auto t_us = static_cast<std::uint64_t>(std::llround(imu.time_s[k] * 1e6));
      ulog += writer.Accel(t_us, imu.accel[k]);
      ulog += writer.Gyro(t_us, imu.gyro[k]);
    }
    return ulog;
  };
  Write("slot.ulg", session(ULogImuWriter::Parameter("CAL_ACC0_ID", 2) +
                            ULogImuWriter::Parameter("CAL_ACC1_ID", 1) +
                            ULogImuWriter::Parameter("CAL_GYRO0_ID", 5) +
                            ULogImuWriter::Parameter("CAL_GYRO1_ID", 3) +
                            ULogImuWriter::Parameter("CAL_GYRO2_ID", 9)));
  const std::string log = Path("slot.ulg");
  ASSERT_EQ(Exec("calibrate " + log + " --gravity 9.81 --gyro " + log + " -q -o " + Path("s.json"))
                .status,
            0);
  CliRun e = Exec("export " + Path("s.json") + " --to px4");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("1\t1\tCAL_ACC1_ID\t1\t6\n"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("1\t1\tCAL_ACC1_XSCALE\t"), std::string::npos) << e.out;
  EXPECT_EQ(e.out.find("\tCAL_ACC0_"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("# CAL_ACC1: sensor_accel instance 0 of the log, device id 1; slot 1: the "
                       "log's CAL_ACC1_ID is its device id"),
            std::string::npos)
      << e.out;
  EXPECT_NE(e.out.find("1\t1\tCAL_GYRO2_ID\t9\t6\n"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("1\t1\tCAL_GYRO2_XOFF\t"), std::string::npos) << e.out;
  // A slot given that contradicts the log's, for either sensor: refused, with the reason (one
  // --instance is both sensors' slot; without it each takes its own).
  e = Exec("export " + Path("s.json") + " --to px4 --instance 0");
  EXPECT_EQ(e.status, 2);
  EXPECT_EQ(e.out, "");
  EXPECT_NE(e.err.find("--instance 0 contradicts the log: its CAL_ACC1_ID is the accelerometer's "
                       "device id 1, so PX4 applies CAL_ACC1 to it (the log's: CAL_ACC0_ID 2, "
                       "CAL_ACC1_ID 1)"),
            std::string::npos)
      << e.err;
  e = Exec("export " + Path("s.json") + " --to px4 --instance 1");
  EXPECT_EQ(e.status, 2);
  EXPECT_NE(e.err.find("--instance 1 contradicts the log: its CAL_GYRO2_ID is the gyroscope's "
                       "device id 9"),
            std::string::npos)
      << e.err;
  // No slot of the log holds the sensor: the first free one, said.
  Write("free.ulg", session(ULogImuWriter::Parameter("CAL_ACC0_ID", 2) +
                            ULogImuWriter::Parameter("CAL_ACC1_ID", 0)));
  ASSERT_EQ(
      Exec("calibrate " + Path("free.ulg") + " --gravity 9.81 -q -o " + Path("f.json")).status, 0);
  e = Exec("export " + Path("f.json") + " --to px4");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("1\t1\tCAL_ACC1_ID\t1\t6\n"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("slot 1: no CAL_ACCn_ID of the log is its device id (the log's: "
                       "CAL_ACC0_ID 2, CAL_ACC1_ID 0): CAL_ACC1 is the first slot it leaves free"),
            std::string::npos)
      << e.out;
  // Every slot another sensor's: refused rather than one replaced unasked.
  Write("full.ulg", session(ULogImuWriter::Parameter("CAL_ACC0_ID", 2) +
                            ULogImuWriter::Parameter("CAL_ACC1_ID", 3) +
                            ULogImuWriter::Parameter("CAL_ACC2_ID", 4) +
                            ULogImuWriter::Parameter("CAL_ACC3_ID", 5)));
  ASSERT_EQ(
      Exec("calibrate " + Path("full.ulg") + " --gravity 9.81 -q -o " + Path("u.json")).status, 0);
  e = Exec("export " + Path("u.json") + " --to px4");
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("every CAL_ACC slot holds another sensor's calibration"), std::string::npos)
      << e.err;
  e = Exec("export " + Path("u.json") + " --to px4 --instance 3");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("slot 3: the instance given; the log's CAL_ACC3_ID is 5, another sensor's"),
            std::string::npos)
      << e.out;
}

// ArduPilot logs a parameter set while the log runs as another PARM record: the value in force
// at the samples is the last one logged before them (issue 47: the first won, and the export
// composed with INS_ACCOFFS_X 0.5 where 0.05 was in force), and a calibration parameter that
// changes during the samples is refused, named with both values and their times.
TEST_F(NativeLogTest, DataFlashParametersAreThoseInForceAtTheSamples) {
  const Vec3 o_true(0.35, -0.21, 0.48), s_true(1.012, 0.991, 1.004);
  const Vec3 o_old(0.05, 0.05, -0.30), s_old(0.995, 1.006, 0.998);
  ModelParameters seen;  // what the records hold under (o_old, s_old), as the compose test
  seen.K = s_old.cwiseQuotient(s_true).asDiagonal();
  seen.bias = (o_true - o_old).cwiseProduct(s_old);
  RawLogSimulation options;
  options.static_s = 2.0;
  options.transition_s = 1.0;
  options.sigma_raw_per_sample = Vec3(1e-3, 1e-3, 1e-3);
  const DataFlashImuWriter writer;
  const char axes[3] = {'X', 'Y', 'Z'};
  // At the start a calibration ten times off in X, then the recalibration, logged before the
  // session at 0.5 s (the samples begin 1 s in).
  const auto session = [&](std::uint64_t recalibrated_us, bool gyro_set = false) {
    std::string out = writer.Header();
    for (int i = 0; i < 3; ++i) {
      out += writer.Parameter(0, std::string("INS_ACCOFFS_") + axes[i],
                              static_cast<float>(i == 0 ? 10 * o_old(i) : o_old(i)));
      out += writer.Parameter(0, std::string("INS_ACCSCAL_") + axes[i],
                              static_cast<float>(i == 0 ? 1.02 * s_old(i) : s_old(i)));
    }
    // A temperature calibration in force, off: what the records were corrected by, kept.
    out +=
        writer.Parameter(0, "INS_TCAL1_ENABLE", 0) + writer.Parameter(0, "INS_TCAL1_ACC1_X", 3000);
    std::string later =
        writer.Parameter(recalibrated_us, "INS_ACCOFFS_X", static_cast<float>(o_old(0))) +
        writer.Parameter(recalibrated_us, "INS_ACCSCAL_X", static_cast<float>(s_old(0)));
    SimulateRawLog(seen, 9.80665, Yang18Directions(), options, [&](double t, const Vec3& a) {
      const auto t_us = static_cast<std::uint64_t>(std::llround(t * 1e6)) + 1000000;
      if (!later.empty() && t_us >= recalibrated_us) out += std::move(later), later.clear();
      if (gyro_set && t_us >= 20000000) {
        out += writer.Parameter(t_us, "INS_GYROFFS_X", 0.01f);
        gyro_set = false;
      }
      out += writer.Sample(t_us, a, Vec3::Zero());
    });
    return out;
  };
  Write("before.bin", session(500000));
  ASSERT_EQ(
      Exec("calibrate " + Path("before.bin") + " --gravity 9.80665 -q -o " + Path("b.json")).status,
      0);
  const nlohmann::json cal = nlohmann::json::parse(Slurp(Path("b.json")));
  const nlohmann::json& in_force = cal["provenance"]["inputs"][0]["stream"]["calibration_in_force"];
  // The log holds float32 values: the doubles they are.
  EXPECT_EQ(in_force["INS_ACCOFFS_X"].get<double>(),
            static_cast<double>(static_cast<float>(o_old(0))));
  EXPECT_EQ(in_force["INS_ACCSCAL_X"].get<double>(),
            static_cast<double>(static_cast<float>(s_old(0))));
  EXPECT_EQ(in_force["INS_TCAL1_ENABLE"], 0);
  EXPECT_EQ(in_force["INS_TCAL1_ACC1_X"], 3000);
  CliRun e = Exec("export " + Path("b.json") + " --to ardupilot -o " + Path("e.param"));
  ASSERT_EQ(e.status, 0) << e.err;
  const std::string text = Slurp(Path("e.param"));
  const auto value = [&](const std::string& name) {
    const std::size_t at = text.find("\n" + name + ",");
    EXPECT_NE(at, std::string::npos) << name << "\n" << text;
    return std::stod(text.substr(at + name.size() + 2));
  };
  EXPECT_NEAR(value("INS_ACCOFFS_X"), o_true(0), 5e-4);  // 0.45 m/s² off with the first value
  EXPECT_NEAR(value("INS_ACCSCAL_X"), s_true(0), 5e-5);  // 2 % off
  // inspect says what was set when.
  e = Exec("inspect " + Path("before.bin"));
  EXPECT_NE(e.out.find("parameter INS_ACCOFFS_X set to 0.0500000007 at 0.500000 s"),
            std::string::npos)
      << e.out;
  e = Exec("inspect --json " + Path("before.bin"));
  const nlohmann::json listed = nlohmann::json::parse(e.out)["parameter_changes"];
  ASSERT_EQ(listed.size(), 2u) << e.out;
  EXPECT_EQ(listed[0]["name"], "INS_ACCOFFS_X");
  EXPECT_EQ(listed[0]["time_s"], 0.5);
  // Recalibrated during the samples: refused, both values and their times named.
  Write("during.bin", session(20000000));
  e = Exec("calibrate " + Path("during.bin") + " --gravity 9.80665 -q -o " + Path("d.json"));
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("the calibration parameter INS_ACCOFFS_X changes from 0.5 (logged at "
                       "0.000000 s) to 0.0500000007 at 20.000000 s, during the samples of IMU"),
            std::string::npos)
      << e.err;
  // A gyroscope's offsets set meanwhile (ArduPilot learns them at boot) are not the
  // accelerometer's calibration.
  Write("gyro.bin", session(500000, true));
  EXPECT_EQ(
      Exec("calibrate " + Path("gyro.bin") + " --gravity 9.80665 -q -o " + Path("g.json")).status,
      0);
}

// Two IMUs published on one ROS topic, told apart by header.frame_id alone (issue 47: read as one
// 200 Hz sensor, verdict ok, the bias the mean of the two): inspect lists the frames, calibrate
// refuses the topic naming them, and --frame-id reads one sensor, whose bias is its own.
TEST_F(NativeLogTest, TwoSensorsOnOneRosTopicAreToldApartByFrame) {
  RawLogSimulation sim;
  sim.static_s = 2.0;
  sim.transition_s = 1.0;
  sim.sigma_raw_per_sample = Vec3::Constant(0.01);
  ModelParameters a, b;
  a.bias = Vec3(0.30, -0.10, 0.05);
  b.bias = Vec3(-0.20, 0.25, -0.15);
  const SimulatedLog la = SimulateRawLog(a, 9.80665, Yang18Directions(), sim);
  sim.seed = 2;
  const SimulatedLog lb = SimulateRawLog(b, 9.80665, Yang18Directions(), sim);
  ASSERT_EQ(la.samples.size(), lb.samples.size());
  RosBagImuWriter writer;
  std::string bytes = writer.Header();
  for (std::size_t i = 0; i < la.samples.size(); ++i) {
    const auto ns = 1700000000000000000ull + static_cast<std::uint64_t>(1e9 * la.time_s[i]);
    bytes += writer.Sample(ns, la.samples[i]);  // a's first: the order the frames are named in
    bytes += writer.Sample(ns + 1000000, lb.samples[i]);
  }
  bytes += writer.Finish();
  const std::string indexed = writer.IndexedHeader();
  bytes.replace(RosBagImuWriter::kHeaderOffset, indexed.size(), indexed);
  // The writer names every message's frame imu_link: sensor a's become imu_000a, b's imu_000b
  // (the same length, in a ROS 1 bag's uncompressed bytes, in the messages' order).
  std::size_t k = 0;
  for (std::size_t at = bytes.find("imu_link"); at != std::string::npos;
       at = bytes.find("imu_link", at + 8), ++k) {
    bytes.replace(at, 8, k % 2 == 0 ? "imu_000a" : "imu_000b");
  }
  ASSERT_EQ(k, 2 * la.samples.size());
  Write("two.bag", bytes);
  const std::string n = std::to_string(la.samples.size());
  const std::string frames = "'imu_000a' (" + n + " messages), 'imu_000b' (" + n + " messages)";
  CliRun e = Exec("inspect " + Path("two.bag"));
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("topic /imu/data: its messages name 2 frames (header.frame_id), several "
                       "sensors on one topic: " +
                       frames + "; read one with --frame-id NAME"),
            std::string::npos)
      << e.out;
  const nlohmann::json listed =
      nlohmann::json::parse(Exec("inspect --json " + Path("two.bag")).out);
  EXPECT_EQ(listed["streams"][0]["frames"][1]["frame_id"], "imu_000b");
  EXPECT_EQ(listed["streams"][0]["frames"][1]["messages"], la.samples.size());
  e = Exec("calibrate " + Path("two.bag") + " -q -o " + Path("two.json"));
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("/imu/data's messages name 2 frames (header.frame_id): " + frames +
                       ": several sensors published on one topic, which read as one would mix "
                       "their readings; choose one with --frame-id"),
            std::string::npos)
      << e.err;
  for (const char* frame : {"imu_000a", "imu_000b"}) {
    SCOPED_TRACE(frame);
    e = Exec("calibrate " + Path("two.bag") + " --frame-id " + frame + " -q -o " + Path("f.json"));
    ASSERT_EQ(e.status, 0) << e.err;
    const nlohmann::json cal = nlohmann::json::parse(Slurp(Path("f.json")));
    const Vec3& bias = std::string(frame) == "imu_000a" ? a.bias : b.bias;
    for (int i = 0; i < 3; ++i) {
      // σ of a bias from 18 positions of 200 samples at 0.01: about 0.0003; 0.01 is 30 of them
      // and a fifth of the two sensors' smallest difference.
      EXPECT_NEAR(cal["sensors"]["accelerometer"]["bias"][i].get<double>(), bias(i), 0.01);
    }
  }
  e = Exec("calibrate " + Path("two.bag") + " --frame-id imu_000c -q -o " + Path("c.json"));
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(
      e.err.find("no message of /imu/data names the frame 'imu_000c' (its frames: " + frames + ")"),
      std::string::npos)
      << e.err;
  // A ULog's topics have no frame; a text file neither.
  e = Exec("calibrate " + kSmall + " --topic sensor_accel --instance 0 --frame-id imu_000a -q -o " +
           Path("u.json"));
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("sensor_accel's messages name no frame (header.frame_id)"),
            std::string::npos)
      << e.err;
  Write("t.csv", "t,x,y,z\n0,0,0,9.8\n0.01,0,0,9.8\n");
  e = Exec("calibrate " + Path("t.csv") + " --frame-id imu_000a -q -o " + Path("t.json"));
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("a frame was given, but this is a text file"), std::string::npos) << e.err;
}

// A topic accelcal cannot decode (issue 47: inspect listed a JSON channel as read, with its
// sensors, and calibrate then refused it): inspect says why, and lists no sensor for it.
TEST_F(NativeLogTest, InspectSaysWhyATopicCannotBeRead) {
  McapImuWriter writer(McapCompression::kNone, "/imu");
  std::string bytes = writer.Header();
  // The Channel record ends the header: its message encoding "cdr" made another.
  const std::size_t at = bytes.rfind("cdr");
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, 3, "cbr");
  for (int k = 0; k < 50; ++k) {
    bytes += writer.Sample(1000000000ull + 10000000ull * std::uint64_t(k), Vec3(0, 0, 9.81));
  }
  bytes += writer.Finish();
  Write("cbr.mcap", bytes);
  CliRun e = Exec("inspect " + Path("cbr.mcap"));
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("topic /imu: accelcal cannot decode its messages: its messages are cbr of a "
                       "ros2msg schema"),
            std::string::npos)
      << e.out;
  EXPECT_EQ(e.out.find("accelerometer"), std::string::npos) << e.out;
  const nlohmann::json doc = nlohmann::json::parse(Exec("inspect --json " + Path("cbr.mcap")).out);
  EXPECT_TRUE(doc["streams"][0]["sensors"].empty());
  EXPECT_NE(doc["streams"][0]["unreadable"].get<std::string>().find("cbr"), std::string::npos);
  e = Exec("calibrate " + Path("cbr.mcap") + " --topic /imu -q -o " + Path("c.json"));
  EXPECT_EQ(e.status, 3);
  EXPECT_NE(e.err.find("accelcal cannot decode the topic /imu"), std::string::npos) << e.err;
}

// PX4's other accelerometer topics, written here as PX4 lays them out (ULog specification):
// sensor_accel_fifo (the driver's every sample, int16 times a scale, up to 32 a message, the last
// at timestamp_sample, dt apart) and vehicle_imu (delta_velocity integrated over
// delta_velocity_dt). A simulated session in each calibrates to the same bytes as the samples they
// hold, written as CSV.
namespace px4 {
template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof(T));
}
std::string Message(char type, const std::string& payload) {
  std::string out;
  Put<std::uint16_t>(&out, static_cast<std::uint16_t>(payload.size()));
  return out + type + payload;
}
// The gyroscope's block of the PX4 export: CAL_GYRO<n>_ID from the sensor_gyro stream's own
// device id (or --gyro-device-id), PRIO, and the offsets, which are the calibrated still rate b_g
// in rad/s (sensor_gyro's unit, which labels the raw unit); PX4 holds no gyroscope scale, and the
// export says what dropping it costs.
TEST_F(NativeLogTest, Px4ExportHoldsTheGyroscopeOffsets) {
  RawLogSimulation options;
  options.static_s = 4.0;
  options.transition_s = 2.0;
  options.sigma_raw_per_sample = Vec3(0.02, 0.02, 0.02);
  GyroSimulation gyro;  // rad/s, as PX4's drivers scale them: 0.2-0.3 % scale errors
  gyro.truth.K << 1.002, 0.001, -0.002, 0.0, 0.997, 0.001, 0.0, 0.0, 1.003;
  gyro.truth.bias = Vec3(0.012, -0.008, 0.005);
  gyro.sigma_raw_per_sample = Vec3(1e-3, 1e-3, 1e-3);
  ModelParameters accel;  // m/s², PX4's sensor_accel
  accel.K = Vec3(1.001, 0.999, 1.002).asDiagonal();
  accel.bias = Vec3(0.05, -0.03, 0.08);
  const SimulatedImuLog log = SimulateImuLog(accel, 9.81, Yang18Directions(), options, gyro);
  const ULogImuWriter writer(7, true, 9);
  std::string ulog = writer.Header();
  for (std::size_t k = 0; k < log.time_s.size(); ++k) {
    const auto t = static_cast<std::uint64_t>(std::llround(log.time_s[k] * 1e6));
    ulog += writer.Accel(t, log.accel[k]);
    ulog += writer.Gyro(t, log.gyro[k]);
  }
  const std::string u = Write("imu.ulg", ulog);
  const CliRun run =
      Exec("calibrate " + u + " --gravity 9.81 --gyro " + u + " -q -o " + Path("u.json"));
  ASSERT_EQ(run.status, 0) << run.err;
  const nlohmann::json cal = nlohmann::json::parse(Slurp(Path("u.json")));
  const nlohmann::json& g = cal["sensors"]["gyroscope"];
  EXPECT_EQ(g["units"]["raw"], "rad/s");  // sensor_gyro's unit by its definition
  CliRun e = Exec("export " + Path("u.json") + " --to px4");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("1\t1\tCAL_ACC0_ID\t7\t6\n"), std::string::npos) << e.out;
  std::string block = "1\t1\tCAL_GYRO0_ID\t9\t6\n1\t1\tCAL_GYRO0_PRIO\t50\t6\n";
  const char axes[3] = {'X', 'Y', 'Z'};
  for (int i = 0; i < 3; ++i) {
    const double b = g["bias"][i];
    // The estimate's σ is about 1e-5 rad/s (1e-3 per sample over 400 still samples a position):
    // 2e-4 is 20 σ, and a tenth of the smallest offset.
    EXPECT_NEAR(b, gyro.truth.bias(i), 2e-4) << i;
    char line[80];
    std::snprintf(line, sizeof line, "1\t1\tCAL_GYRO0_%cOFF\t%.9g\t9\n", axes[i], b);
    block += line;
  }
  EXPECT_NE(e.out.find(block), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("# CAL_GYRO0: sensor_gyro instance 0 of the log, device id 9"),
            std::string::npos)
      << e.out;
  // The scale PX4 cannot hold: the rate error (K_g - I) w, at most the largest singular value
  // of the estimated K_g - I (the truth's is 0.433 %) times |w|.
  Mat33 K_g;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) K_g(r, c) = g["K"][r][c];
  }
  char dropped[200];
  std::snprintf(dropped, sizeof dropped,
                "dropped from the gyroscope: the scale and misalignment K_g, which PX4 does not "
                "hold (a rate error of up to %.3g %% of the rate)",
                100 * Eigen::JacobiSVD<Mat33>(Mat33(K_g - Mat33::Identity())).singularValues()(0));
  EXPECT_NE(e.err.find(dropped), std::string::npos) << dropped << "\n" << e.err;
  e = Exec("export " + Path("u.json") + " --to px4 --gyro-device-id 11 --instance 1");
  EXPECT_NE(e.out.find("1\t1\tCAL_GYRO1_ID\t11\t6\n"), std::string::npos) << e.out;
  EXPECT_NE(e.out.find("1\t1\tCAL_ACC1_ID\t7\t6\n"), std::string::npos) << e.out;
  EXPECT_EQ(Exec("export " + Path("u.json") + " --to kalibr --gyro-device-id 5").status, 2);
  // The gyroscope's input record removed by hand: the accelerometer's record of the same file
  // (sensor_accel, device id 7) is not taken for the gyroscope's.
  nlohmann::json edited = cal;
  edited["provenance"]["inputs"].erase(edited["provenance"]["inputs"].size() - 1);
  Write("edited.json", edited.dump());
  e = Exec("export " + Path("edited.json") + " --to px4");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("# CAL_GYRO0: the calibrated sensor; its device id is unknown"),
            std::string::npos)
      << e.out;
  EXPECT_EQ(e.out.find("\tCAL_GYRO0_ID\t"), std::string::npos) << e.out;
  // The rates' unit vouched for with --gyro-raw-unit: the same block.
  e = Exec("export " + Path("u.json") + " --to px4 --gyro-raw-unit rad/s");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find(block), std::string::npos) << e.out;
  // Rates labelled deg/s that are rad/s (K_g 57 times the unit's): no offsets PX4 would apply to
  // rates of another scale; the rest is exported, and the reason said.
  nlohmann::json mislabelled = cal;
  mislabelled["sensors"]["gyroscope"]["units"]["raw"] = "deg/s";
  Write("deg.json", mislabelled.dump());
  e = Exec("export " + Path("deg.json") + " --to px4");
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_EQ(e.out.find("CAL_GYRO0_"), std::string::npos) << e.out;
  EXPECT_NE(e.err.find("they are not in 'deg/s'"), std::string::npos) << e.err;
}

// A log of one topic of `format` ("name:fields"), subscribed as message id 0.
std::string Header(const std::string& format) {
  std::string out = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35, 0x01};
  Put<std::uint64_t>(&out, 0);
  out += Message('B', std::string(40, '\0'));
  out += Message('F', format);
  std::string add(1, '\0');
  Put<std::uint16_t>(&add, 0);
  return out + Message('A', add + format.substr(0, format.find(':')));
}
}  // namespace px4

TEST_F(NativeLogTest, Px4FifoAndVehicleImuCalibrateAsTheirSamples) {
  ModelParameters truth;  // m/s², as PX4's drivers give them
  truth.K << 1.004, 0, 0, 0.002, 0.996, 0, -0.001, 0.003, 1.002;
  truth.bias = Vec3(0.12, -0.08, 0.2);
  RawLogSimulation options;
  options.rate_hz = 1000;
  options.static_s = 3.0;
  options.transition_s = 1.5;
  options.sigma_raw_per_sample = Vec3(0.02, 0.02, 0.02);
  const SimulatedLog log = SimulateRawLog(truth, 9.80665, Yang18Directions(), options);
  // sensor_accel_fifo: 4 samples a message, 1000 us apart, in counts of 16 g / 32768.
  const float scale = static_cast<float>(9.80665 * 16 / 32768), dt = 1000.0f;
  std::string fifo = px4::Header(
      "sensor_accel_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;"
      "float dt;float scale;uint8_t samples;int16_t[32] x;int16_t[32] y;int16_t[32] z;");
  std::string fifo_csv = "time_us,x,y,z\n";
  char line[160];
  const std::size_t n = log.samples.size() / 4 * 4;
  for (std::size_t m = 0; m < n; m += 4) {
    const auto last_us = static_cast<std::uint64_t>(std::llround(log.time_s[m + 3] * 1e6));
    std::string d;
    px4::Put<std::uint16_t>(&d, 0);
    px4::Put<std::uint64_t>(&d, last_us);
    px4::Put<std::uint64_t>(&d, last_us);
    px4::Put<std::uint32_t>(&d, 4325386);
    px4::Put<float>(&d, dt);
    px4::Put<float>(&d, scale);
    px4::Put<std::uint8_t>(&d, 4);
    std::int16_t counts[3][32] = {};
    for (int k = 0; k < 4; ++k) {
      for (int a = 0; a < 3; ++a) {
        counts[a][k] = static_cast<std::int16_t>(std::lround(log.samples[m + k](a) / scale));
      }
      std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g\n",
                    static_cast<double>(last_us) - (3 - k) * static_cast<double>(dt),
                    counts[0][k] * static_cast<double>(scale),
                    counts[1][k] * static_cast<double>(scale),
                    counts[2][k] * static_cast<double>(scale));
      fifo_csv += line;
    }
    d.append(reinterpret_cast<const char*>(counts), sizeof counts);
    fifo += px4::Message('D', d);
  }
  // vehicle_imu: each sample's velocity change over 1000 us, float32.
  std::string imu = px4::Header(
      "vehicle_imu:uint64_t timestamp;uint64_t timestamp_sample;uint32_t accel_device_id;"
      "uint32_t gyro_device_id;float[3] delta_angle;float[3] delta_velocity;"
      "uint16_t delta_angle_dt;uint16_t delta_velocity_dt;uint8_t delta_angle_clipping;"
      "uint8_t delta_velocity_clipping;uint8_t accel_calibration_count;"
      "uint8_t gyro_calibration_count;");
  std::string imu_csv = "time_us,x,y,z\n";
  for (std::size_t k = 0; k < log.samples.size(); ++k) {
    const auto t_us = static_cast<std::uint64_t>(std::llround(log.time_s[k] * 1e6));
    std::string d;
    px4::Put<std::uint16_t>(&d, 0);
    px4::Put<std::uint64_t>(&d, t_us);
    px4::Put<std::uint64_t>(&d, t_us);
    px4::Put<std::uint32_t>(&d, 4325386);
    px4::Put<std::uint32_t>(&d, 2293786);
    for (int a = 0; a < 3; ++a) px4::Put<float>(&d, 0.0f);
    float dv[3];
    for (int a = 0; a < 3; ++a) {
      dv[a] = static_cast<float>(log.samples[k](a) * 0.001);
      px4::Put<float>(&d, dv[a]);
    }
    px4::Put<std::uint16_t>(&d, 1000);
    px4::Put<std::uint16_t>(&d, 1000);
    d.append(4, '\0');
    imu += px4::Message('D', d);
    const double interval_s = 1000 * 1e-6;
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g\n",
                  static_cast<unsigned long long>(t_us), dv[0] / interval_s, dv[1] / interval_s,
                  dv[2] / interval_s);
    imu_csv += line;
  }
  struct Case {
    const char* name;
    const std::string* log;
    const std::string* csv;
  };
  for (const Case& c : {Case{"fifo", &fifo, &fifo_csv}, Case{"vehicle_imu", &imu, &imu_csv}}) {
    const std::string u = Write(std::string(c.name) + ".ulg", *c.log);
    const std::string v = Write(std::string(c.name) + ".csv", *c.csv);
    const CliRun a = Exec("calibrate " + u + " -o " + Path("a.json"));
    const CliRun b =
        Exec("calibrate " + v + " --time-unit us --raw-units m/s2 -o " + Path("b.json"));
    ASSERT_EQ(a.status, 0) << c.name << a.err;
    ASSERT_EQ(b.status, 0) << c.name << b.err;
    EXPECT_EQ(Calibration(Path("a.json")).dump(1), Calibration(Path("b.json")).dump(1)) << c.name;
    const nlohmann::json stream =
        nlohmann::json::parse(Slurp(Path("a.json")))["provenance"]["inputs"][0]["stream"];
    EXPECT_EQ(stream["device_id"], 4325386) << c.name;
    EXPECT_EQ(stream["corrected"], std::string(c.name) == "vehicle_imu") << c.name;
  }
  // A FIFO message that says more samples than its arrays hold: named.
  std::string bad = fifo;
  // (The last message's payload: msg id, two times, device id, dt, scale, samples, the arrays.)
  const std::size_t payload = 2 + 8 + 8 + 4 + 4 + 4 + 1 + 3 * 64;
  const std::size_t samples_at = fifo.size() - payload + (2 + 8 + 8 + 4 + 4 + 4);
  bad[samples_at] = 40;
  const CliRun refused = Exec("calibrate " + Write("bad.ulg", bad) + " -o " + Path("x.json"));
  EXPECT_NE(refused.err.find("a FIFO message of 40 samples 1000 us apart (at most 32"),
            std::string::npos)
      << refused.err;
}

// noise streams its log: a ULog of a still sensor (white noise) gives the same analysis as its
// samples written as CSV.
TEST_F(NativeLogTest, NoiseOfAStillULogIsTheNoiseOfItsSamplesAsCsv) {
  const ULogImuWriter writer;
  std::string ulog = writer.Header(), csv = "time_us,x,y,z\n";
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 0.02);
  char line[160];
  for (int k = 0; k < 60000; ++k) {
    const auto t = static_cast<std::uint64_t>(k) * 5000;  // 200 Hz
    const Vec3 v(n(rng), n(rng), 9.81 + n(rng));
    const auto f = [](double x) { return static_cast<double>(static_cast<float>(x)); };
    ulog += writer.Accel(t, v);
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g\n", static_cast<unsigned long long>(t),
                  f(v(0)), f(v(1)), f(v(2)));
    csv += line;
  }
  const std::string u = Write("still.ulg", ulog), c = Write("still.csv", csv);
  const CliRun a = Exec("noise " + u + " --json");
  const CliRun b = Exec("noise " + c + " --time-unit us --json");
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  nlohmann::json ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out);
  ja.erase("source");
  jb.erase("source");
  ja["accelerometer"].erase("source");
  jb["accelerometer"].erase("source");
  EXPECT_EQ(ja.dump(1), jb.dump(1));
}

TEST_F(NativeLogTest, SeveralStreamsAreListedAndOneIsChosen) {
  const CliRun several = Exec("calibrate " + kSmall);
  EXPECT_EQ(several.status, 3) << several.err;  // an input error
  for (const char* named : {"sensor_combined instance 0 (1298 samples at 199.7 Hz)",
                            "sensor_accel instance 1 (device id 3670050, 6 samples",
                            "choose one with --topic and --instance"}) {
    EXPECT_NE(several.err.find(named), std::string::npos) << several.err;
  }
  // One chosen: it is read (six samples at 1 Hz are no calibration session, which is said).
  const CliRun one = Exec("calibrate " + kSmall + " --topic sensor_accel --instance 1");
  EXPECT_NE(one.status, 0);
  EXPECT_EQ(one.err.find("several"), std::string::npos) << one.err;
  const CliRun none = Exec("calibrate " + kSmall + " --topic vehicle_nothing");
  EXPECT_NE(none.err.find("no stream of topic vehicle_nothing with samples (its topics: "),
            std::string::npos)
      << none.err;
  const CliRun absent = Exec("calibrate " + kSmall + " --topic sensor_accel --instance 7");
  EXPECT_NE(absent.err.find("no stream of topic sensor_accel with instance 7 with samples: "),
            std::string::npos)
      << absent.err;
  const CliRun field = Exec("calibrate " + kSmall +
                            " --topic sensor_combined --columns gyro_rad[0],gyro_rad[1],nope");
  EXPECT_NE(field.err.find("\"nope\", which sensor_combined does not have (its fields: "),
            std::string::npos)
      << field.err;
  const CliRun unit = Exec("calibrate " + kSmall + " --topic sensor_combined --time-unit s");
  EXPECT_NE(unit.err.find("a PX4 ULog's timestamp is in microseconds by its specification, not "
                          "in s"),
            std::string::npos)
      << unit.err;
  const CliRun twice = Exec("calibrate " + kSmall + " --topic sensor_accel --instance 0 " +
                            "--columns timestamp,x,x,z");
  EXPECT_NE(twice.err.find("--columns reads the field x twice"), std::string::npos) << twice.err;
  const CliRun empty = Exec("calibrate " + kSmall + " --topic ''");
  EXPECT_NE(empty.err.find("--topic: an empty topic name"), std::string::npos) << empty.err;
}

TEST_F(NativeLogTest, TopicOnATextFileIsRefused) {
  const std::string csv = Write("p.csv", PositionsCsv(12));
  const CliRun r = Exec("calibrate " + csv + " --topic sensor_accel");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("a topic was given, but this is a text file"), std::string::npos) << r.err;
}

// A vehicle that crashed leaves its log cut inside a message: the whole messages calibrate, and
// the calibration says where the log stopped.
TEST_F(NativeLogTest, LogCutShortIsUsedWithAWarning) {
  ASSERT_EQ(
      Exec("simulate --scenario yang2012 --raw --format ulog --duration 20 -o " + Path("s.ulg"))
          .status,
      0);
  const std::string all = Slurp(Path("s.ulg"));
  const std::string cut = Write("cut.ulg", all.substr(0, all.size() - 17));
  const CliRun r = Exec("calibrate " + cut + " -o " + Path("cut.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("warning: " + cut + ": the log ends inside a message at byte "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("after 42786 whole messages: those were used"), std::string::npos) << r.err;
  const nlohmann::json j = nlohmann::json::parse(Slurp(Path("cut.json")));
  EXPECT_EQ(j["verdict"], "warnings");  // not a failure
  EXPECT_NE(j.dump().find("log_cut_short"), std::string::npos);
}

}  // namespace
}  // namespace accelcal::test
