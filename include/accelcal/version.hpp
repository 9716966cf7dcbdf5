#pragma once
/// @file version.hpp
/// The library's version (the CMake project's), as the tool's --version and a calibration file's
/// `provenance.accelcal_version` state it.

#include <string_view>

namespace accelcal {

/// "MAJOR.MINOR.PATCH".
std::string_view Version();

}  // namespace accelcal
