#pragma once
/// @file calibration_file.hpp
/// The calibration file: JSON, `format` "accelcal-calibration", `version` 1. Keys are documented
/// in docs/calibration-file.md. Writing is deterministic (same result → same bytes).

#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/positions.hpp"

namespace accelcal {

/// What the file needs besides the CalibrationResult.
struct CalibrationFileInfo {
  ForceUnit unit = ForceUnit::kMetersPerSecond2;
  std::string raw_unit = "raw";  ///< label of the raw unit, e.g. "counts"
  std::string source;            ///< input file name (the first, when there are several)
  /// Several input files (sessions of one device, positions pooled): their names, written as
  /// `sources`, and the index into them of each position, written as `positions[].file`.
  std::vector<std::string> sources;
  std::vector<int> position_source;
  std::vector<Position> positions;  ///< the positions that were fitted, same order as the result
  /// When the linear and quadratic models were compared (model "auto", or "quadratic" with the
  /// linear fit as comparison): written as `model_selection`.
  const ModelSelection* model_selection = nullptr;
  std::string model_requested;  ///< "linear", "quadratic" or "auto"
  /// Written as `verdict` and `diagnostics`; when null, Diagnose() of the result, the positions
  /// and the model selection (without the log's findings).
  const Diagnosis* diagnosis = nullptr;
};

/// Serialises a calibration as the JSON document (2-space indented, trailing newline).
std::string CalibrationToJson(const CalibrationResult& result, const CalibrationFileInfo& info);

/// What applying a calibration needs, read back from a file.
struct LoadedCalibration {
  ModelKind model = ModelKind::kLinear;
  Frame frame = Frame::kXFirst;
  ModelParameters params;
  double gravity = 0;
  ForceUnit unit = ForceUnit::kMetersPerSecond2;
  std::string raw_unit = "raw";      ///< `units.raw` (a label given at calibration)
  std::vector<Vec3> position_means;  ///< `positions[].mean` [raw]; empty when the file has none
  std::string source;                ///< `source`: the calibrated input's name, when present
  /// `verdict` ("ok", "warnings", "failed"); empty in a file written before diagnoses existed.
  std::string verdict;
  /// `covariance` in the order of ParameterSlots(model, frame); empty when the file has null.
  Eigen::MatrixXd covariance;
};

/// Parses a calibration file's text; throws InputError naming `source` for anything missing,
/// mistyped or inconsistent (unknown format/version, K not triangular as its frame requires,
/// non-finite numbers, a covariance that is not P x P for the model's P parameters).
LoadedCalibration ParseCalibrationJson(const std::string& text, const std::string& source);

}  // namespace accelcal
