#pragma once
/// @file export.hpp
/// A calibration in the formats of the tools that apply it (`accelcal export CAL.json --to F`).
/// Every export states its convention, and when the target cannot hold the model it says what is
/// dropped and how large the resulting error is on the calibration's own positions. The exact
/// conversion formulas are in docs/conventions.md.
///
/// accelcal's model: p = K f + b + k2 ∘ f² (p raw reading, f specific force in the body frame of
/// `frame`, K triangular: calibrate.hpp, docs/model.md). Every format below instead maps a reading
/// to a corrected specific force, f = M (p − o) or f = diag(s) (p − o).
///
/// Text from outside (the raw-unit label, the log's path in `source`) never changes what a file
/// holds beyond its comments. Where the format has escaping, it is escaped: yaml writes every
/// string as a double-quoted scalar (`\"`, `\\`, `\t`, `\n`, `\r`, `\xHH`, `\uHHHH`) that YAML
/// 1.1 and 1.2 readers read back exactly; json is the calibration file itself. Where it goes into
/// a comment line (px4 and ardupilot `#` lines, kalibr's YAML comments, the c-header's block
/// comment) it is made one line of visible characters, VisibleLine below: control characters and
/// line separators become `\n`, `\r`, `\t`, `\xHH` or `\uHHHH`, bytes that are no UTF-8 `\xHH`; in
/// the c-header a space is put inside `*/`, `/*` and the `??/` trigraph (`* /`, `/ *`, `?? /`).
/// The conventions (ExportResult::convention) hold the label the same way. Every number is
/// written the same in every locale (a host program's setlocale(LC_NUMERIC, ...) changes none).

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/noise_file.hpp"

namespace accelcal {

enum class ExportFormat {
  kJson,    ///< "json": the native calibration file, unchanged
  kYaml,    ///< "yaml": the same document in YAML
  kKalibr,  ///< "kalibr": Kalibr's imu.yaml with the scale-misalignment intrinsics
  /// "px4": CAL_ACCn_{X,Y,Z}OFF and CAL_ACCn_{X,Y,Z}SCALE (QGroundControl .params), with
  /// CAL_GYROn_{X,Y,Z}OFF when the file has a gyroscope (PX4 holds a gyroscope's offsets only)
  kPx4,
  kArduPilot,  ///< "ardupilot": INS_ACC[n]OFFS_{X,Y,Z} and INS_ACC[n]SCAL_{X,Y,Z} (.param)
  kCHeader,    ///< "c-header": constants and an inline correction function for firmware
  kImuTk,      ///< "imutk": imu_tk's CalibratedTriad .calib (misalignment, scale, bias)
  /// "kalibr-imu": Kalibr's input imu.yaml (kalibr_calibrate_imu_camera --imu): the noise
  /// densities, random walks, update rate and topic (needs ExportOptions::noise with both sensors)
  kKalibrImu,
  /// "ros": sensor_msgs/Imu covariances, each axis' variance of one sample (density² · rate; needs
  /// ExportOptions::noise). These two hold the noise alone: their ExportLoss is empty.
  kRos,
  /// "openvins": OpenVINS' kalibr_imu_chain.yaml (model kalibr): Ta, Tw, R_IMUtoACC, R_IMUtoGYRO,
  /// Tg and the noise (needs ExportOptions::noise with both sensors)
  kOpenVins,
  /// "basalt": Basalt's calib.json IMU fields, calib_accel_bias and calib_gyro_bias (its inverse
  /// model, biases in calibrated units) and the noise per axis; the camera fields empty
  kBasalt,
};
std::string_view ToString(ExportFormat format);
std::optional<ExportFormat> ExportFormatFromString(std::string_view text);
template <>
struct EnumNames<ExportFormat> {
  static constexpr std::pair<ExportFormat, std::string_view> kTable[] = {
      {ExportFormat::kJson, "json"},
      {ExportFormat::kYaml, "yaml"},
      {ExportFormat::kKalibr, "kalibr"},
      {ExportFormat::kPx4, "px4"},
      {ExportFormat::kArduPilot, "ardupilot"},
      {ExportFormat::kCHeader, "c-header"},
      {ExportFormat::kImuTk, "imutk"},
      {ExportFormat::kKalibrImu, "kalibr-imu"},
      {ExportFormat::kRos, "ros"},
      {ExportFormat::kOpenVins, "openvins"},
      {ExportFormat::kBasalt, "basalt"}};
};
/// All formats, in the order above (help texts, tests).
const std::vector<ExportFormat>& AllExportFormats();

struct ExportOptions {
  /// Overrides the calibration's raw-unit label for the formats that need readings in m/s²
  /// (kalibr, px4, ardupilot): "m/s2" or "g". Empty: the file's `units.raw`.
  std::string raw_unit;
  /// Overrides the gyroscope's raw-unit label for the formats that need rates in rad/s (kalibr):
  /// "rad/s" or "deg/s". Empty: the file's `sensors.gyroscope.units.raw`.
  std::string gyro_raw_unit;
  /// Sensor instance: PX4 CAL_ACC<n> (0-based), ArduPilot INS_ACC / INS_ACC2 / INS_ACC3 (0, 1, 2).
  /// Unset: ArduPilot's 0; PX4's the slot whose CAL_ACC<n>_ID (CAL_GYRO<n>_ID) in the log's
  /// parameters is the sensor's device id, else the first the log leaves free (the export says
  /// which and why). PX4 refuses a given one that contradicts the log's (std::invalid_argument).
  std::optional<int> instance;
  /// PX4: the CAL_ACC<n>_ID to write (the sensor's device id, by which PX4 matches a calibration
  /// to its sensor). Unset: the device id of the ULog stream the calibration was made from (its
  /// provenance), else none is written and the export says PX4 will not apply it.
  std::optional<std::uint64_t> device_id;
  /// PX4: the CAL_GYRO<n>_ID to write, as device_id for the gyroscope (unset: the device id of
  /// the gyroscope's ULog stream, else none is written).
  std::optional<std::uint64_t> gyro_device_id;
  /// ArduPilot: the parameters in force when the log was recorded (a .param file's names and
  /// values), for a calibration of data they had already corrected (IMU, ACC records). Unset:
  /// the log's own PARM values, which the calibration file's provenance records.
  std::optional<std::map<std::string, double>> current_params;
  /// Prefix of the C identifiers (c-header).
  std::string c_prefix = "accelcal";
  /// The sensor a one-sensor format (imutk) holds: "accelerometer" or "gyroscope". The c-header
  /// holds both when the file has both; json and yaml hold the whole file.
  std::string sensor = "accelerometer";
  /// The sensor's noise (`accelcal noise --json`, ParseNoiseJson): kalibr-imu and ros need it;
  /// kalibr writes its keys beside the model when given.
  std::optional<ImuNoise> noise;
  /// The topic of the IMU's sensor_msgs/Imu messages (kalibr-imu, openvins, kalibr's `rostopic`):
  /// a ROS name (a letter, '/' or '~' first, then letters, digits, '_' and '/').
  std::string rostopic = "/imu0";

  /// Why these options cannot export to `format`, or nothing: a value out of its range (instance,
  /// PX4's and ArduPilot's slots, sensor, gyro_raw_unit, rostopic, c_prefix), and, of the fields
  /// named in `given` (those the caller set), one that `format` has no use for: an option
  /// silently ignored is a mistake. Fields are named as themselves, marked {{name}} (OptionError);
  /// ExportCalibration applies the value rules to any caller.
  std::optional<std::string> Validate(ExportFormat format,
                                      const std::vector<std::string>& given = {}) const;
};

/// What the target format could not hold, measured on the calibration's own positions (the means
/// in the file): the exported correction against the full model, both in the specific-force unit
/// of the calibration.
struct ExportLoss {
  std::string dropped;   ///< empty: the export is exact (to round-off)
  int positions = 0;     ///< how many positions the errors are measured on (0: none in the file)
  double max_error = 0;  ///< max_k |f_export,k − f_k|
  double rms_error = 0;  ///< RMS_k |f_export,k − f_k|
  double norm_rms_full = 0;    ///< RMS_k (|f_k| − g), the full model
  double norm_rms_export = 0;  ///< RMS_k (|f_export,k| − g)
};

struct ExportResult {
  std::string text;        ///< the file's content
  std::string convention;  ///< what the exported numbers mean (direction, units, frame)
  ExportLoss loss;
  /// The file's gyroscope calibration (LoadedCalibration::gyroscope) went into the export: false
  /// when the file has none or the format does not hold it (the caller says so).
  bool gyroscope_included = false;
  /// Why a format that can hold the gyroscope left it out (empty: it did not, or cannot hold it).
  std::string gyroscope_omitted;
  /// What the gyroscope's export could not hold ("" when exact or not included).
  std::string gyroscope_dropped;
};

/// `native_json` is the calibration file's text (for json and yaml, which carry all of it).
/// Throws DataError when the format cannot express this calibration at all (kalibr, px4 and
/// ardupilot need readings in m/s² or g), or when a format that applies it to readings in m/s²
/// (px4, ardupilot, kalibr, openvins, basalt) would be given an accelerometer no sensor has in that
/// unit: scales outside 2/3 to 3/2, offsets beyond 0.5 g. A gyroscope no sensor has in rad/s
/// (scales as those, offsets beyond 150 deg/s) is left out with the reason in gyroscope_omitted,
/// or refused (DataError) by openvins and basalt, whose files state a gyroscope in any case.
/// std::invalid_argument for bad options.
ExportResult ExportCalibration(const LoadedCalibration& calibration, const std::string& native_json,
                               ExportFormat format, const ExportOptions& options = {});

/// YAML (block style) of a JSON document; numbers, booleans and null keep their JSON spelling,
/// so numbers read back exactly; strings are double-quoted scalars, escaped as above.
std::string JsonToYaml(const std::string& json_text);

/// `text` (a label, a path) as one line of visible characters, for a comment or header line of a
/// text file: tab, line feed and carriage return become `\t`, `\n`, `\r`; the other control
/// characters (C0, DEL, C1), U+2028, U+2029, U+FEFF, U+FFFE and U+FFFF `\xHH` (below U+0100) or
/// `\uHHHH`; a byte that is no UTF-8 `\xHH`. Everything else, printable Unicode too, is kept.
std::string VisibleLine(std::string_view text);

}  // namespace accelcal
