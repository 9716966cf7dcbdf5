#pragma once
/// @file mat_writer.hpp
/// Writing a MATLAB MAT-file (Level 5, uncompressed; specification: MathWorks, "MAT-File Format")
/// of one real double matrix, column by column: for simulated sessions (`accelcal simulate --raw
/// --format mat`, a 4 × N matrix whose columns are the samples: time [s], x, y, z) and the tests
/// of the reader (native_log.hpp). A matrix is stored column-major, so a matrix whose columns are
/// the samples is written as they come, its size given first, never held whole. No time of
/// writing is stored: the same samples give the same bytes.

#include <cstdint>
#include <string>

namespace accelcal {

class MatMatrixWriter {
 public:
  /// A `rows` × `columns` double matrix named `variable`. Throws std::invalid_argument for a name
  /// that is not a MATLAB identifier (a letter, then up to 62 letters, digits or '_'), no rows, or
  /// a matrix beyond what Level 5 holds (int32 dimensions; at most 2^32 - 1 bytes in one
  /// variable: about 134 million four-row columns).
  MatMatrixWriter(std::string variable, std::uint32_t rows, std::uint64_t columns);
  /// The file's 128-byte header, then the variable's element up to its data.
  std::string Header() const;
  /// One column: `rows` values. Throws std::logic_error past the columns announced.
  std::string Column(const double* values);
  /// Throws std::logic_error unless every column announced was given (the file would not be the
  /// matrix its header says). Returns the bytes that end the file (none: doubles fill 8-byte
  /// boundaries).
  std::string Finish() const;

 private:
  std::string variable_;
  std::uint32_t rows_;
  std::uint64_t columns_, written_ = 0;
};

}  // namespace accelcal
