#pragma once
/// @file report.hpp
/// The calibration report: one self-contained HTML page (inline SVG, no scripts, no network) a
/// person reads at a glance — the raw signal with the static intervals shaded, |f| − g per position
/// before and after calibration and held out, the measured directions on the sphere (both
/// hemispheres, equal-area), the residuals per axis, the parameters in engineering units with ±1σ,
/// and warnings. Built from the calibration file's text, so `calibrate --report` and
/// `report CAL.json [LOG]` give the same page. Deterministic: the same input gives the same bytes.

#include <string>
#include <vector>

#include "accelcal/log_reader.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {

struct ReportInput {
  std::string calibration_json;            ///< the calibration file's text (calibration_file.hpp)
  std::string calibration_name;            ///< its file name, for messages and the title
  const RawLog* log = nullptr;             ///< the recording, when available: the raw-signal plot
  std::vector<RejectedInterval> rejected;  ///< still runs the detection did not keep
};

/// Throws InputError (naming calibration_name) when the calibration text is not a valid file.
std::string RenderReport(const ReportInput& input);

/// What the report warns about, in order (also used by the CLI summary and the tests).
std::vector<std::string> ReportWarnings(const ReportInput& input);

}  // namespace accelcal
