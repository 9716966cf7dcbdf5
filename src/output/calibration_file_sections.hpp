#pragma once
// The sections of a calibration file that more than one reader takes (calibration_file_read.cpp),
// and the gyroscope's (calibration_file_gyroscope.cpp).
#include <string>
#include <utility>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "output/json_reader.hpp"

namespace accelcal::internal {

// `doc`'s `covariance`: n × n numbers, symmetric with a diagonal ≥ 0 (`what` names its
// parameters in the error).
Eigen::MatrixXd ReadSquareCovariance(const Reader& r, const ordered_json& doc, std::size_t n,
                                     const std::string& what);

// `diagnostics`: the findings of the checks the calibration passed or failed.
void ReadDiagnostics(const Reader& r, const ordered_json& doc, LoadedCalibration& cal);

// A thermal section's `temperature_range`: the temperatures its fit spans, to which its
// polynomials are held; T_ref within them.
std::pair<double, double> ReadTemperatureRange(const Reader& in, const ordered_json& t,
                                               double t_ref_c);
// Its checks, for a range read otherwise.
void CheckTemperatureRange(const Reader& in, std::pair<double, double> range, double t_ref_c);

// A sensor's `K` that can be inverted: not singular to a double's precision, and not so small
// that a reading times its inverse is no physical quantity (its smallest singular value at least
// 1e-12 raw per unit: any sensor's is far above it). Fails naming `key` otherwise.
void CheckInvertible(const Reader& r, const Mat33& K, const char* key);

// `sensors.gyroscope` (calibration_file_gyroscope.cpp), written and read by one description.
ordered_json GyroscopeSection(const UnitGyroscope& g, ForceUnit force_unit);
UnitGyroscope ReadGyroscope(const Reader& r, const ordered_json& doc);

}  // namespace accelcal::internal
