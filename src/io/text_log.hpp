#pragma once
// Reading a text log's table in blocks (text_log.cpp): its columns found from the columns option,
// its header or its column count, its rows parsed, for ReadInput, ParseInput and StreamRawLog
// (log_reader.cpp).
#include <functional>
#include <string>
#include <vector>

#include "accelcal/log_reader.hpp"
#include "io/input_file.hpp"

namespace accelcal::internal {

// A number for a message: whole numbers in full (device ids such as PX4's 2490378), others to 6
// significant digits.
std::string ShortNumber(double v);

// What a raw log read in blocks hands on after each block: the block's rows (data->raw, and their
// instance values when the file has an instance column), to be taken and cleared.
using BlockSink = std::function<void(InputData* data, std::vector<double>* instances)>;
// The columns a raw log read in blocks was found to have, told before its first block.
struct BlockColumns {
  bool time = false;
  std::string time_name;      // the header's name of the time column ("" without a header)
  std::string instance_name;  // the instance column's name; "" without one
};

inline constexpr const char* kNoInstanceColumn =
    "an instance was chosen, but the file has no instance column (i, instance, multi_id, "
    "device_id, imu, imu_id, sensor_id, id)";

// The rows of a text log (or, with `sink`, handed on block by block, `columns` told first).
InputData ParseBlocks(TextBlocks& blocks, const std::string& source, const ReadOptions& options,
                      const BlockSink* sink = nullptr, BlockColumns* columns = nullptr);

}  // namespace accelcal::internal
