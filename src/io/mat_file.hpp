#pragma once
// MATLAB MAT-files (level 5: MATLAB 5 to 7, compressed or not; 7.3, HDF5-based), read with
// libmatio, the field's library for them: a numeric two-dimensional variable is a table whose
// rows are samples (or positions), read as the same numbers written as text would be.

#include <cstddef>
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

/// A numeric matrix read, its rows the samples: `values` row after row.
struct MatTable {
  std::string variable;
  std::size_t rows = 0, columns = 0;
  bool transposed = false;  ///< stored with the samples as its columns, and read turned
  std::vector<double> values;
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
