#pragma once
/// @file parameter_file.hpp
/// An autopilot's parameter file, as its ground stations save one: Mission Planner's and
/// ArduPilot's `.param` (`NAME,VALUE` per line), MAVProxy's (`NAME VALUE`), QGroundControl's
/// (`vehicle component NAME VALUE type`, tab-separated). Comments begin with '#'.

#include <map>
#include <string>
#include <string_view>

namespace accelcal {

/// The parameters of `text` (named `source` in errors), by name. Throws InputError naming the
/// line for a line that is none of the forms, a value that is not a finite number, a name given
/// twice (with different values), or no parameter at all.
std::map<std::string, double> ParseParameterFile(std::string_view text, const std::string& source);

}  // namespace accelcal
