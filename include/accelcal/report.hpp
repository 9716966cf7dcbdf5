#pragma once
/// @file report.hpp
/// The calibration report: one self-contained HTML page (inline SVG, no scripts, no network) a
/// person reads at a glance — the raw signal with the static intervals shaded, |f| − g per position
/// before and after calibration and held out, the measured directions on the sphere (both
/// hemispheres, equal-area), the residuals per axis, the parameters in engineering units with ±1σ,
/// and warnings. Built from the calibration file as read (ParseCalibrationJson), so `calibrate
/// --report` and `report CAL.json [LOG]` give the same page; the report reads no JSON itself.
/// Deterministic: the same input gives the same bytes.

#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {

struct ReportInput {
  LoadedCalibration calibration;           ///< the calibration file, read
  std::string calibration_name;            ///< its file name, for the title when it names no source
  const RawLog* log = nullptr;             ///< the recording, when available: the raw-signal plot
  std::vector<RejectedInterval> rejected;  ///< still runs the detection did not keep
};

std::string RenderReport(const ReportInput& input);

/// What the report warns about, in order: the file's own diagnosis (its warnings and failures),
/// and the still periods the log's detection did not use when the file does not list them (also
/// used by the CLI's `report` and the tests).
std::vector<std::string> ReportWarnings(const ReportInput& input);

}  // namespace accelcal
