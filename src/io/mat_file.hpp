#pragma once
// MATLAB MAT-files (level 5: MATLAB 5 to 7, compressed or not; 7.3, HDF5-based), read with
// libmatio, the field's library for them: a numeric two-dimensional variable is a table whose
// rows are samples (or positions), read as the same numbers written as text would be.

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace accelcal::internal {

/// A file that begins as a MAT-file's descriptive text does ("MATLAB 5.0 MAT-file",
/// "MATLAB 7.3 MAT-file").
bool IsMatFile(std::string_view first_bytes);

/// One variable of a MAT-file, as `whos` would list it.
struct MatVariable {
  std::string name;
  std::string type;  ///< its class ("double", "single", "int16", ..., "struct", "char")
  std::vector<std::size_t> dims;
  /// A real numeric matrix: what accelcal reads.
  bool numeric_matrix = false;
};

/// The largest matrix read, in values: its samples, parsed, take about 9 bytes a value (36 a
/// time,x,y,z row) beside libmatio's copy of the data (up to 8 a value), so that a small
/// compressed file cannot ask for more than about half a GiB (a 1 MB file had held 2^28 values
/// of one byte, 2.26 GB). A session of 8.4 M samples of time,x,y,z (2.3 hours at 1 kHz).
inline constexpr std::size_t kMaxMatValues = std::size_t{1} << 25;

/// A numeric matrix read, its rows the samples, each value read from libmatio's data where it
/// is (in the variable's own class: a copy as doubles had taken eight times a byte matrix).
struct MatTable {
  std::string variable;
  std::size_t rows = 0, columns = 0;
  bool transposed = false;  ///< stored with the samples as its columns, and read turned
  /// The value of sample `row`, field `column`.
  double At(std::size_t row, std::size_t column) const;
  std::shared_ptr<const void> data;  ///< libmatio's variable
};

/// The variables of the MAT-file at `path`. Throws InputError naming the file for what libmatio
/// cannot open or read.
std::vector<MatVariable> ListMatVariables(const std::string& path);

/// Reads variable `name` of the MAT-file at `path` (empty: its only numeric matrix) as a table.
/// A matrix with more than 16 columns and at most 16 rows holds its samples as columns (a 4 x N
/// time,x,y,z) and is read turned. Throws InputError naming the file, and listing the variables
/// when none or several could be meant.
MatTable ReadMatTable(const std::string& path, const std::string& name);

}  // namespace accelcal::internal
