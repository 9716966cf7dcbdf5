#include "accelcal/orientation_file.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/platform_model.hpp"
#include "accelcal/sha256.hpp"
#include "core/text_format.hpp"
#include "io/number_parser.hpp"
#include "io/text_lines.hpp"

namespace accelcal {

namespace {

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& ch : out) ch = static_cast<char>(internal::AsciiLower(ch));
  return out;
}

// The layout a header names, with the column count it needs (yaw optional).
bool LayoutOfHeader(const std::vector<std::string_view>& fields, OrientationLayout* layout) {
  std::vector<std::string> names;
  for (std::string_view f : fields) names.push_back(Lower(f));
  const auto is = [&](std::initializer_list<const char*> expected) {
    if (names.size() != expected.size()) return false;
    std::size_t i = 0;
    for (const char* e : expected) {
      if (names[i++] != e) return false;
    }
    return true;
  };
  if (is({"x", "y", "z"}) || is({"cx", "cy", "cz"})) {
    *layout = OrientationLayout::kDirections;
  } else if (is({"roll_deg", "pitch_deg"}) || is({"roll_deg", "pitch_deg", "yaw_deg"})) {
    *layout = OrientationLayout::kRollPitchYaw;
  } else if (is({"qw", "qx", "qy", "qz"})) {
    *layout = OrientationLayout::kQuaternions;
  } else if (is({"theta1_deg", "theta2_deg", "theta3_deg"})) {
    *layout = OrientationLayout::kGimbalAngles;
  } else {
    return false;
  }
  return true;
}

std::string Number6(double v) {
  char buf[32];
  internal::FormatTo(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

Eigen::Quaterniond AttitudeFromRollPitchYaw(double roll_rad, double pitch_rad, double yaw_rad) {
  return Eigen::AngleAxisd(yaw_rad, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch_rad, Vec3::UnitY()) *
         Eigen::AngleAxisd(roll_rad, Vec3::UnitX());
}

Vec3 UpDirectionInBody(const Eigen::Quaterniond& body_to_level) {
  return body_to_level.conjugate() * Vec3::UnitZ();
}

OrientationFile ParseOrientations(std::string_view text, const std::string& source) {
  OrientationFile out;
  bool header_seen = false;
  std::size_t columns = 3;
  internal::LineReader reader(text, source);
  internal::Line line;
  while (reader.Next(&line)) {
    const std::size_t line_number = line.number;
    const std::vector<std::string_view> fields = internal::SplitLine(line.text);
    if (fields.empty()) continue;
    double first = 0;
    if (!header_seen && out.directions.empty() && !internal::ParseNumber(fields[0], &first)) {
      if (!LayoutOfHeader(fields, &out.layout)) {
        throw InputError(source, line_number,
                         "unknown header: expected x,y,z or roll_deg,pitch_deg[,yaw_deg] or "
                         "qw,qx,qy,qz or theta1_deg,theta2_deg,theta3_deg");
      }
      header_seen = true;
      columns = fields.size();
      continue;
    }
    if (fields.size() != columns) {
      throw InputError(source, line_number,
                       "expected " + std::to_string(columns) + " columns, found " +
                           std::to_string(fields.size()));
    }
    double v[4] = {0, 0, 0, 0};
    for (std::size_t i = 0; i < fields.size(); ++i) {
      if (!internal::ParseNumber(fields[i], &v[i]) || !std::isfinite(v[i])) {
        throw InputError(source, line_number,
                         "column " + std::to_string(i + 1) + " ('" + std::string(fields[i]) +
                             "') is not a finite number");
      }
    }
    const std::size_t position = out.directions.size() + 1;
    Vec3 c;
    if (out.layout == OrientationLayout::kDirections) {
      c = Vec3(v[0], v[1], v[2]);
      if (!(std::abs(c.norm() - 1.0) <= 1e-3)) {
        throw InputError(source, line_number,
                         "direction " + std::to_string(position) + " (" + Number6(c(0)) + ", " +
                             Number6(c(1)) + ", " + Number6(c(2)) +
                             ") is not a unit vector (norm " + Number6(c.norm()) + ")");
      }
      c.normalize();
    } else if (out.layout == OrientationLayout::kGimbalAngles) {
      constexpr double kDeg = 3.14159265358979323846 / 180.0;
      c = PlatformUp(Vec3(v[0], v[1], v[2]) * kDeg);
    } else {
      Eigen::Quaterniond q;
      if (out.layout == OrientationLayout::kRollPitchYaw) {
        constexpr double kDeg = 3.14159265358979323846 / 180.0;
        q = AttitudeFromRollPitchYaw(v[0] * kDeg, v[1] * kDeg, v[2] * kDeg);
      } else {
        q = Eigen::Quaterniond(v[0], v[1], v[2], v[3]);
        if (!(std::abs(q.norm() - 1.0) <= 1e-3)) {
          throw InputError(source, line_number,
                           "quaternion " + std::to_string(position) + " has norm " +
                               Number6(q.norm()) + ", not 1");
        }
        q.normalize();
      }
      out.attitudes.push_back(q);
      c = UpDirectionInBody(q);
    }
    out.directions.push_back(c);
    out.lines.push_back(line_number);
  }
  if (out.directions.empty()) throw InputError(source, 0, "no orientations in the file");
  return out;
}

OrientationFile ReadOrientations(const std::string& path) {
  const std::string text = ReadFileToString(path, kMaxSmallFileBytes);
  OrientationFile file = ParseOrientations(text, path);
  file.bytes = text.size();
  file.sha256 = Sha256Hex(text);
  return file;
}

}  // namespace accelcal
