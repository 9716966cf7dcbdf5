#pragma once
/// @file table_file.hpp
/// A small table of numbers (the gimbal stages' files of paper 003: commanded angles and mean
/// outputs per position), read with the same line reader, tokenizer and number parser as every
/// other text input: fields separated by commas (a line with one) or blanks, `#` comments and
/// blank lines skipped, a header allowed on the first line that is not blank, numbers as in logs
/// (a leading '+' too).

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace accelcal {

/// The rows of `text`, each of exactly `columns` finite numbers. Throws InputError naming
/// `source` and the line: a row of another width or with a field that is no number ("expected N
/// numbers"), a value that is not finite, or no row at all.
std::vector<std::vector<double>> ParseNumberTable(std::string_view text, const std::string& source,
                                                  std::size_t columns);
/// ParseNumberTable of a file (at most kMaxSmallFileBytes).
std::vector<std::vector<double>> ReadNumberTable(const std::string& path, std::size_t columns);

}  // namespace accelcal
