// The bag 2.0 format as both our writer (bag_writer.h) and our structure check
// (bag_check.cpp) read it: "#ROSBAG V2.0\n", then records
// "<header length><header><data length><data>", the header a list of "<field length>name=value";
// integers little-endian, times as sec then nsec.
#pragma once

#include <cstddef>
#include <cstdint>

namespace attitude_propagator {
namespace tools {
namespace bag_format {

inline constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
inline constexpr std::size_t kVersionLength = sizeof kVersionLine - 1;

/// The `op` field of a record header.
enum Op : std::uint8_t {
  kMessage = 0x02,
  kBagHeader = 0x03,
  kIndex = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07
};

}  // namespace bag_format
}  // namespace tools
}  // namespace attitude_propagator
