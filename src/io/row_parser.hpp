#pragma once
// The data rows of a delimited log (log_reader): each row scanned once, left to right, reading
// only the selected columns, with every check of the row and its fields.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/log_reader.hpp"
#include "io/number_parser.hpp"
#include "io/row_template.hpp"
#include "io/text_lines.hpp"

namespace accelcal::internal {

/// Column roles: time, x, y, z, count, sx, sy, sz, instance, temperature.
enum Role { kTime, kX, kY, kZ, kCount, kSx, kSy, kSz, kInstance, kTemperature, kRoles };

/// The column of each role; -1 = absent.
struct Layout {
  int column[kRoles];
};

class RowParser {
 public:
  /// `ncols` (at most kMaxFields) columns per row separated by `delim`, read as `layout` says;
  /// `raw`: rows are samples (else positions). The references must outlive this.
  RowParser(const std::string& source, Delimiter delim, std::size_t ncols, const Layout& layout,
            bool raw, const std::function<void(std::size_t, std::size_t)>& progress);
  /// The temperature column was found by its header, not asked for: a value that is no
  /// temperature in °C is left out (NaN) and counted, not an error.
  void LenientTemperature() { lenient_temperature_ = true; }
  /// With LenientTemperature: the values left out, and the first one's line and text.
  std::size_t temperatures_left_out() const { return left_out_; }
  std::uint32_t first_left_out_line() const { return first_left_out_line_; }
  const std::string& first_left_out() const { return first_left_out_; }

  /// Parses one block of whole lines (TextBlocks) into `data` (and the instance column's values
  /// into `instances`); returns the lines read so far. `skip_first`: the block's first line is
  /// the header. Throws InputError, naming the line, for a row that is not one.
  std::uint32_t Parse(std::string_view block, std::size_t block_offset, std::size_t total,
                      std::uint32_t lines_before, char eol, bool skip_first, std::size_t* rows,
                      InputData* data, std::vector<double>* instances) const;

 private:
  const char* FastRow(const char* p, const char* last, double* values, NumberShape* shapes,
                      FieldSeen* seen) const;
  void ParseFields(const Line& line, double* values) const;
  void ParseField(const Line& line, std::size_t column, const char* field_begin,
                  const char* field_end, double* value) const;
  Position MakePosition(const Vec3& xyz, const double* values, std::uint32_t line_number) const;
  // Throws InputError for a temperature outside kTemperatureRange_C (lenient: NaN, counted).
  double CheckTemperature(double t_c, std::uint32_t line_number) const;
  void LeaveOut(std::uint32_t line_number, const std::string& text) const;

  const std::string& source_;
  Delimiter delim_;
  std::size_t ncols_;
  Layout layout_;
  bool raw_;
  const std::function<void(std::size_t, std::size_t)>& progress_;
  int role_of_column_[kMaxFields];
  bool every_column_read_ = false;  // every column has a role (a row template may hold them)
  bool lenient_temperature_ = false;
  mutable std::size_t left_out_ = 0;
  mutable std::uint32_t first_left_out_line_ = 0;
  mutable std::string first_left_out_;
};

}  // namespace accelcal::internal
