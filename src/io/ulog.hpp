#pragma once
// PX4 ULog (.ulg), read from its specification (PX4 documentation, "ULog File Format"): a 16-byte
// header (magic "ULog" 01 12 35, version, start time [µs]), then messages of `uint16 size, uint8
// type` and `size` bytes: the definitions (B flag bits, F formats, I/M information, P/Q
// parameters), then the data (A subscribes a format under a message id and multi id, D is one
// message of it, R unsubscribes; L/C logged strings, S sync, O dropout; P a changed parameter).
// Little-endian, packed as the format lists its fields (padding fields named `_padding…`).

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/binary_stream.hpp"
#include "io/decoded_log.hpp"

namespace accelcal::internal {

/// The header's first 7 bytes.
inline constexpr unsigned char kULogMagic[7] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};
bool IsULog(std::string_view first_bytes);

/// Reads a whole ULog from `in` (at its first byte), keeping the messages of the subscriptions
/// `keep` accepts (topic, multi id). Throws InputError (the file, the byte offset, the reason)
/// for what is not a ULog or is corrupt: an unknown message type, a format that does not parse
/// or refers to an unknown type, a data message whose size is not its format's, an incompatible
/// flag this reader does not know.
/// A subscription's instance is its multi id; its time, the `timestamp` field; its parameters,
/// the P messages of the definitions; its information, the I messages whose value is a string.
DecodedLog ReadULog(BinaryStream& in, const KeepStream& keep, const StoreColumns& store = {});

}  // namespace accelcal::internal
