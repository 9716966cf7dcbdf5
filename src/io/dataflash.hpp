#pragma once
// ArduPilot DataFlash (.bin), read from its self-description (ArduPilot's "Logs" documentation and
// its LogStructure.h): records `A3 95 type` then the fields of that type, packed, the whole
// record as long as its FMT record says. FMT (type 128, 89 bytes) defines a type: its number,
// record length, name (char[4]), format (char[16]: one character per field) and column labels
// (char[64], comma-separated). Little-endian.

#include <string_view>

#include "io/binary_stream.hpp"
#include "io/decoded_log.hpp"

namespace accelcal::internal {

/// A log that begins with a FMT record (`A3 95 80`).
bool IsDataFlash(std::string_view first_bytes);

/// Reads a whole DataFlash log from `in` (at its first byte), keeping the records of the streams
/// `keep` accepts. A stream is a message type's instance: its `I` field when it has one, else 0.
/// Its time is its `TimeUS` field; the parameters are the log's PARM records (their first value);
/// text fields (n, N, Z) and arrays (a) are left out of the columns, and the scaled integer
/// types (c, C, e, E: hundredths; L: 1e-7 degrees) are given scaled. Throws InputError (the file,
/// the byte offset, the reason) for a record that does not begin A3 95, a type no FMT defined, a
/// FMT whose format does not parse or whose length is not its fields'.
DecodedLog ReadDataFlash(BinaryStream& in, const KeepStream& keep, const StoreColumns& store = {});

}  // namespace accelcal::internal
