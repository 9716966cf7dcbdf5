#include "accelcal/table_file.hpp"

#include <cmath>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "io/number_parser.hpp"
#include "io/text_lines.hpp"

namespace accelcal {

std::vector<std::vector<double>> ParseNumberTable(std::string_view text, const std::string& source,
                                                  std::size_t columns) {
  std::vector<std::vector<double>> rows;
  internal::LineReader reader(text, source);
  internal::Line line;
  bool first = true;  // a header is allowed on the first line that is not blank only
  while (reader.Next(&line)) {
    const std::vector<std::string_view> fields = internal::SplitLine(line.text);
    std::vector<double> row;
    bool numeric = true;
    for (const std::string_view field : fields) {
      double v = 0;
      if (!internal::ParseNumber(field, &v)) {
        numeric = false;
        break;
      }
      row.push_back(v);
    }
    const bool header = first && !numeric && row.empty();
    first = false;
    if (header) continue;
    if (!numeric || row.size() != columns) {
      throw InputError(source, line.number, "expected " + std::to_string(columns) + " numbers");
    }
    for (const double v : row) {
      if (!std::isfinite(v)) throw InputError(source, line.number, "a value is not finite");
    }
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw InputError(source, 0, "no rows");
  return rows;
}

std::vector<std::vector<double>> ReadNumberTable(const std::string& path, std::size_t columns) {
  return ParseNumberTable(ReadFileToString(path, kMaxSmallFileBytes), path, columns);
}

}  // namespace accelcal
