#pragma once
/// @file error.hpp
/// Exceptions thrown by accelcal for bad input. Solver outcomes (non-convergence) are reported in
/// the Summary, not thrown.

#include <cstddef>
#include <stdexcept>
#include <string>

namespace accelcal {

/// A file or text could not be read as what it should be. Carries the file and 1-based line.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::size_t line, std::string reason);
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }  ///< 0 when the error is not tied to one line.
  const std::string& reason() const { return reason_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string reason_;
};

/// The data were read, but a calibration cannot be computed from them (too few positions,
/// unobservable geometry, no static interval, ...). The message names the problem.
class DataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A DataError where an estimator that returns no Summary (the gyroscope's, whose failure to
/// converge leaves nothing to report) did not converge.
class NotConvergedError : public DataError {
 public:
  using DataError::DataError;
};

}  // namespace accelcal
