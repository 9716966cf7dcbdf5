#pragma once
/// @file error.hpp
/// Exceptions thrown by accelcal for bad input. Solver outcomes (non-convergence) are reported in
/// the Summary, not thrown.

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>

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
  explicit DataError(const std::string& message, std::string file = "")
      : std::runtime_error(message), file_(std::move(file)) {}
  /// The file it is about when that is not the calculation's main input (the gyroscope's log
  /// beside the accelerometer's); empty: the main input, or none.
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

/// A DataError where an estimator that returns no Summary (the gyroscope's, whose failure to
/// converge leaves nothing to report) did not converge.
class NotConvergedError : public DataError {
 public:
  using DataError::DataError;
};

/// Options of a request that cannot be used as given, alone or together (calibrate_unit.hpp).
/// what() names each option as the Python keywords do (the tool's long options with `_` for
/// `-`); marked() is the same text with each name marked {{name}}, for an edge that names
/// options otherwise (RenderOptionNames): one rule, each edge's own words.
class OptionError : public std::invalid_argument {
 public:
  explicit OptionError(const std::string& marked);
  const std::string& marked() const { return marked_; }

 private:
  std::string marked_;
};

/// `marked` with each {{name}} replaced by `name_of(name)` (a flag of the tool, a keyword of
/// Python); text without marks comes back as it is. The names are lowercase words of letters,
/// digits and `_`: other braces are left alone.
std::string RenderOptionNames(const std::string& marked,
                              const std::function<std::string(const std::string&)>& name_of);

}  // namespace accelcal
