#pragma once
/// @file noise_report.hpp
/// The noise report (`accelcal noise --report`): one self-contained HTML page, per sensor a
/// log-log plot of the overlapping Allan deviation of each axis with its confidence band and the
/// fitted IEEE model, the terms with their uncertainty, and what the terms do not describe.
/// Inline SVG, no scripts; the same input gives the same bytes.

#include <array>
#include <string>
#include <vector>

#include "accelcal/noise.hpp"
#include "accelcal/noise_model.hpp"

namespace accelcal {

struct NoiseReportSensor {
  std::string name;         ///< "accelerometer", "gyroscope"
  std::string source;       ///< its log
  std::string sample_unit;  ///< of the samples, the plot's and B's unit ("m/s2", "rad/s", "raw")
  /// Per term (Q, N, B, K, R by NoiseTerm): the unit the table shows it in and the factor from
  /// the analysis' value (in sample units) to it.
  std::array<std::string, kNoiseTerms> term_unit;
  std::array<double, kNoiseTerms> term_factor{1, 1, 1, 1, 1};
  const NoiseAnalysis* analysis = nullptr;        ///< not null
  std::array<std::vector<std::string>, 3> notes;  ///< per axis: what the terms do not describe
};

struct NoiseReportInput {
  std::string title;      ///< the log's name, for the heading
  std::string time_note;  ///< how the time column was read (or that the rate was given)
  std::string verdict;    ///< "passed" or "failed: ..."
  std::vector<NoiseReportSensor> sensors;
};

/// Throws std::invalid_argument for a sensor without its analysis.
std::string RenderNoiseReport(const NoiseReportInput& input);

}  // namespace accelcal
