#pragma once
// Python's CalibrationResult (py_calibration.cpp), and its pickled state (py_state.cpp).
#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/positions.hpp"

namespace accelcal::python {

// A calibration with what it was fitted to and its diagnosis: Python's CalibrationResult.
struct PyCalibration {
  CalibrationResult result;
  std::optional<ModelSelection> selection;  // model "auto", or "quadratic" with held-out errors
  std::string model_requested;
  ForceUnit unit = ForceUnit::kMetersPerSecond2;
  std::vector<Position> positions;  // the fitted positions, in the result's order
  std::vector<Vec3> mean_sigmas;    // the 1σ of each one's mean as the fit took it (or none)
  std::string source;               // the input file, "" from arrays
  std::string raw_unit = "raw";     // the label of the readings' unit (the file's raw_unit)
  // Several input files (sessions of one unit): their names and each position's file index.
  std::vector<std::string> sources;
  std::vector<int> position_source;
  std::optional<BiasModelSelection> bias_model_selection;  // bias_model "auto"
  int max_excluded = OutlierOptions{}.max_excluded;
  Diagnosis diagnosis;
  Provenance provenance;  // the function and its arguments, the file read (to_json writes it)
  // The gyroscope calibrated from the same recording (calibrate_log's gyro options), with its log
  // and the label of its raw unit.
  std::optional<UnitGyroscope> gyroscope;
};

/// The whole of a result as bytes (CBOR), every double's bits kept: what pickle stores.
std::string SaveState(const PyCalibration& c);
/// The result SaveState saved; ValueError for bytes that are not one, or of another version.
PyCalibration LoadState(const std::string& bytes);

}  // namespace accelcal::python
