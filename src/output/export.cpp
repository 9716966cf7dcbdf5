// Exports of a calibration to the formats of other tools (export.hpp, docs/conventions.md): the
// options' checks and the dispatch to the targets, one file each (export_<target>.cpp, their shared
// pieces in export_common.hpp), and accelcal's own file as JSON or YAML, which holds everything.
#include "accelcal/export.hpp"

#include <algorithm>
#include <stdexcept>

#include "accelcal/error.hpp"

#include "output/export_common.hpp"

namespace accelcal {

namespace {

// A ROS name as ROS 2 (rcl's topic validation) and ROS 1 take it: an optional '/' or "~/", then
// tokens joined by single '/', each starting with a letter or '_', then letters, digits and '_'
// (no empty token: no "//", no trailing '/').
bool IsRosName(std::string_view name) {
  if (name.substr(0, 2) == "~/") {
    name.remove_prefix(2);
  } else if (!name.empty() && name[0] == '/') {
    name.remove_prefix(1);
  }
  if (name.empty()) return false;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = std::min(name.find('/', start), name.size());
    const std::string_view token = name.substr(start, end - start);
    if (token.empty() || exports::IsAsciiDigit(token[0]) ||
        !std::all_of(token.begin(), token.end(), exports::IsIdentifierChar)) {
      return false;
    }
    if (end == name.size()) return true;
    start = end + 1;
  }
}

}  // namespace

std::string_view ToString(ExportFormat format) { return NameOf(format); }

std::optional<ExportFormat> ExportFormatFromString(std::string_view text) {
  return FromName<ExportFormat>(text);
}

const std::vector<ExportFormat>& AllExportFormats() {
  static const std::vector<ExportFormat> all = [] {
    std::vector<ExportFormat> v;
    for (const auto& [format, name] : EnumNames<ExportFormat>::kTable) v.push_back(format);
    return v;
  }();
  return all;
}

std::string VisibleLine(std::string_view text) { return internal::VisibleLine(text); }

namespace {
ExportResult ExportFormatted(const LoadedCalibration& cal, const std::string& native_json,
                             ExportFormat format, const ExportOptions& options);
}  // namespace

ExportResult ExportCalibration(const LoadedCalibration& cal, const std::string& native_json,
                               ExportFormat format, const ExportOptions& options) {
  ExportResult out = ExportFormatted(cal, native_json, format, options);
  // The gyroscope's offsets over temperature: only accelcal's own file and PX4's TC_G hold them.
  const bool holds = format == ExportFormat::kJson || format == ExportFormat::kYaml ||
                     format == ExportFormat::kPx4;
  if (out.gyroscope_included && !holds && cal.gyroscope->thermal &&
      cal.gyroscope->thermal->bias.degree() > 0) {
    out.gyroscope_dropped = exports::Join(
        out.gyroscope_dropped,
        internal::Format(
            "the offsets' change with temperature (degree %d about T_ref = %.4g degC): the "
            "offsets are those at T_ref",
            cal.gyroscope->thermal->bias.degree(), cal.gyroscope->thermal->bias.t_ref_c));
  }
  return out;
}

namespace {

// Which formats use each option (ExportOptions' fields).
struct OptionUse {
  const char* option;
  std::vector<ExportFormat> formats;
};

const std::vector<OptionUse>& OptionUses() {
  using F = ExportFormat;
  static const std::vector<OptionUse> uses = {
      {"raw_unit", {F::kKalibr, F::kOpenVins, F::kBasalt, F::kPx4, F::kArduPilot}},
      {"gyro_raw_unit", {F::kKalibr, F::kOpenVins, F::kBasalt, F::kPx4}},
      {"instance", {F::kPx4, F::kArduPilot}},
      {"c_prefix", {F::kCHeader}},
      {"sensor", {F::kImuTk}},
      {"noise", {F::kKalibrImu, F::kRos, F::kKalibr, F::kOpenVins, F::kBasalt}},
      {"rostopic", {F::kKalibrImu, F::kKalibr, F::kOpenVins}},
      {"device_id", {F::kPx4}},
      {"gyro_device_id", {F::kPx4}},
      {"current_params", {F::kArduPilot}},
  };
  return uses;
}

// The formats by name, as a sentence lists them: "a, b and c".
std::string Listed(const std::vector<ExportFormat>& formats) {
  std::string out;
  for (std::size_t i = 0; i < formats.size(); ++i) {
    if (i > 0) out += i + 1 == formats.size() ? " and " : ", ";
    out += ToString(formats[i]);
  }
  return out;
}

// A C identifier's prefix: a letter or '_' first, then letters, digits and '_'.
std::optional<std::string> CPrefixProblem(const std::string& prefix) {
  if (prefix.empty() || exports::IsAsciiDigit(prefix[0])) {
    return "{{c_prefix}} must start with a letter or '_'";
  }
  if (!std::all_of(prefix.begin(), prefix.end(), exports::IsIdentifierChar)) {
    return "{{c_prefix}} may hold only letters, digits and '_'";
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> ExportOptions::Validate(ExportFormat format,
                                                   const std::vector<std::string>& given) const {
  for (const OptionUse& use : OptionUses()) {
    const bool used =
        std::find(use.formats.begin(), use.formats.end(), format) != use.formats.end();
    if (!used && std::find(given.begin(), given.end(), use.option) != given.end()) {
      return "{{" + std::string(use.option) + "}} is for " + Listed(use.formats) + "; " +
             std::string(ToString(format)) + " has no use for it";
    }
  }
  if (instance && *instance < 0) return "{{instance}} must be >= 0";
  if (format == ExportFormat::kPx4 && instance && *instance > 3) {
    return "PX4 has calibration slots 0 to 3 (CAL_ACC0 to CAL_ACC3)";
  }
  if (format == ExportFormat::kArduPilot && instance && *instance > 2) {
    return "ArduPilot has accelerometers 0, 1 and 2";
  }
  if (sensor != "accelerometer" && sensor != "gyroscope") {
    return "{{sensor}} must be \"accelerometer\" or \"gyroscope\"";
  }
  if (!gyro_raw_unit.empty() && gyro_raw_unit != "rad/s" && gyro_raw_unit != "deg/s") {
    return "{{gyro_raw_unit}} must be rad/s or deg/s";
  }
  if (!IsRosName(rostopic)) {
    return "{{rostopic}} must be a ROS name: '/' or '~/' (or nothing) first, then tokens joined "
           "by '/', each a letter or '_' followed by letters, digits and '_'";
  }
  if (sensor == "gyroscope" && format != ExportFormat::kImuTk) {
    return "{{sensor}} \"gyroscope\" is for the imutk format (the c-header holds both sensors; "
           "json and yaml the whole file)";
  }
  if (format == ExportFormat::kCHeader) return CPrefixProblem(c_prefix);
  return std::nullopt;
}

namespace {
ExportResult ExportFormatted(const LoadedCalibration& cal, const std::string& native_json,
                             ExportFormat format, const ExportOptions& options) {
  if (auto why = options.Validate(format)) throw OptionError(*why);
  ExportResult out;
  switch (format) {
    case ExportFormat::kJson:
    case ExportFormat::kYaml:
      out.text = format == ExportFormat::kJson ? native_json : JsonToYaml(native_json);
      out.convention =
          "accelcal's calibration file (docs/calibration-file.md): p = K f + b + k2 "
          ".* f^2, " +
          exports::DescribeUnits(cal) + ", " + std::string(ToString(cal.frame)) + " body frame";
      out.loss = exports::MeasureLoss(
          cal, [&](const Vec3& p) { return SpecificForce(cal.params, p); }, "", true);
      out.gyroscope_included = cal.has_gyroscope();
      return out;
    case ExportFormat::kKalibr:
      return exports::Kalibr(cal, options);
    case ExportFormat::kPx4:
      return exports::Px4(cal, options);
    case ExportFormat::kArduPilot:
      return exports::ArduPilot(cal, options);
    case ExportFormat::kCHeader:
      return exports::CHeader(cal, options);
    case ExportFormat::kImuTk:
      return options.sensor == "gyroscope" ? exports::ImuTkGyroscope(cal) : exports::ImuTk(cal);
    case ExportFormat::kKalibrImu:
      return exports::KalibrImu(cal, options);
    case ExportFormat::kRos:
      return exports::RosCovariance(cal, options);
    case ExportFormat::kOpenVins:
      return exports::OpenVins(cal, options);
    case ExportFormat::kBasalt:
      return exports::Basalt(cal, options);
  }
  throw std::invalid_argument("unknown export format");
}
}  // namespace

}  // namespace accelcal
