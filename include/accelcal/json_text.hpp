#pragma once
/// @file json_text.hpp
/// The one JSON writer of accelcal: every JSON document the library and the tool write (the
/// calibration file's future layout, `--json` outputs) goes through JsonText, so that they share
/// one layout, one number format and one string escaping.
///
/// Layout: the top level one member per line; a nested container on one line when it holds no
/// array of objects (a vector, a matrix, a record of numbers), else one member per line, indented
/// by two spaces per level. Numbers: integers as integers, doubles as the shortest decimal that
/// reads back as the same double (`std::to_chars`, no locale), non-finite doubles as null.
/// Strings: RFC 8259 escaping; invalid UTF-8 replaced by U+FFFD.

#include <string>

#include <nlohmann/json.hpp>

namespace accelcal {

/// `doc` as text in the layout above, ending in a newline.
std::string JsonText(const nlohmann::ordered_json& doc);

}  // namespace accelcal
