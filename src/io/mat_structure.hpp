#pragma once
// Every size a Level 5 MAT-file claims (MathWorks, "MAT-File Format": data elements, each a tag of
// type and byte count; a matrix's flags, dimensions, name and parts; compressed variables
// holding zlib streams of elements) checked against what holds it, before libmatio reads the
// file: libmatio allocates what a file claims (a 4 GB name in a 4 kB file took 4.2 GB).

#include <cstdint>
#include <optional>
#include <string>

namespace accelcal::internal {

/// The largest a compressed variable may inflate to: the largest matrix read (kMaxMatValues,
/// 2^25) as doubles, and its headers. Beyond it the variable is refused, as a zip bomb would be
/// (a 1 MB file inflating to 1 GiB, the bound before, had taken 22 s and 2.26 GB).
inline constexpr std::uint64_t kMaxMatInflatedBytes = (std::uint64_t{1} << 28) + (1u << 16);

/// Why the Level 5 MAT-file at `path` cannot be handed to libmatio: an element that claims more
/// bytes than its container (or the file) holds, a matrix whose dimensions claim more values than
/// its data holds, a compressed variable that does not inflate or inflates past
/// kMaxMatInflatedBytes (kMaxFileInflatedBytes all of them, decompress.hpp), nesting deeper
/// than 64. std::nullopt when every claim holds, and for a MAT-file 7.3 (HDF5, read by its
/// library).
std::optional<std::string> CheckMatStructure(const std::string& path);

}  // namespace accelcal::internal
