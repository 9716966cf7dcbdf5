#pragma once
// MCAP (.mcap, ROS 2's default bag format since Iron), read from its specification (mcap.dev,
// "MCAP Format Specification", major version 0): the magic 89 "MCAP0" 0D 0A, then records of
// `uint8 opcode, uint64 length` and their content, little-endian: Header, Schema (a message
// type's definition), Channel (a topic, its schema and message encoding), Message (a channel, its
// log time [ns] and the encoded message), Chunk (records compressed with lz4 or zstd, or not,
// with the CRC-32 of the records), the index and summary records (not needed: records are read in
// order, so that a recording never closed is read too), Data End and Footer, the magic again.
// Records may grow new fields at their end, which are skipped.

#include <string_view>

#include "io/binary_stream.hpp"
#include "io/decoded_log.hpp"

namespace accelcal::internal {

/// The 8 bytes an MCAP file begins (and ends) with.
inline constexpr char kMcapMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};
bool IsMcap(std::string_view first_bytes);

/// Reads a whole MCAP file from `in` (at its first byte), decoding the messages of the topics
/// `keep` accepts: CDR messages of ros2msg schemas (ROS 2) and ROS 1 messages of ros1msg ones.
/// A stream is a topic (instance 0); its type, the schema's name; its time [µs], the messages'
/// log time. Throws InputError (the file, the byte offset, the reason) for what is not MCAP or is
/// corrupt: a record that does not parse, a chunk that does not decompress or fails its CRC-32, a
/// message of a channel never defined, a message that is not its type's.
DecodedLog ReadMcap(BinaryStream& in, const KeepStream& keep, const StoreColumns& store = {});

}  // namespace accelcal::internal
