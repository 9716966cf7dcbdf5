#pragma once
// ROS 1 bags (.bag, format 2.0), read from their specification (ROS wiki, "Bags/Format/2.0"):
// the line "#ROSBAG V2.0", then records of `uint32 header_len, header, uint32 data_len, data`,
// a header being fields `uint32 len, name=value`, its `op` the record's kind: the bag header
// (0x03), chunks (0x05: compression none, bz2 or lz4, and the records they hold), connections
// (0x07: a topic, its type and the type's definition), messages (0x02: a connection and a time),
// and the index (0x04, 0x06), which this reader does not need: it reads the records in order,
// so that a bag whose recorder was killed (no index, its last chunk open) is read too.

#include <string_view>

#include "io/binary_stream.hpp"
#include "io/decoded_log.hpp"

namespace accelcal::internal {

/// A file that begins "#ROSBAG V" (any version: others are refused with their number).
bool IsRosBag(std::string_view first_bytes);

/// Reads a whole bag from `in` (at its first byte), decoding the messages of the topics `keep`
/// accepts. A stream is a topic (instance 0), its type the connection's (`sensor_msgs/Imu`), its
/// columns its type's numeric fields (ros_message.hpp), its time [µs] the record's (when the
/// message was recorded). Throws InputError (the file, the byte offset, the reason) for what is
/// not such a bag or is corrupt: a record or header that does not parse, a chunk that does not
/// decompress, a message of a connection never defined, a message whose bytes are not its type's.
DecodedLog ReadRosBag(BinaryStream& in, const KeepStream& keep, const StoreColumns& store = {});

}  // namespace accelcal::internal
